"""The sensor catalog: the built-in sensors by name, built by the twin from its options."""

from __future__ import annotations

import numpy as np

from amr_twin.model.config import load_config
from amr_twin.model.worlds import uwb_anchors_xy_m
from amr_twin.sensors.catalog import SENSORS
from amr_twin.assembly.twin import Twin, TwinOptions


def test_the_built_in_sensors_are_registered_in_order():
    assert SENSORS.names()[:3] == ("imu", "lidar", "uwb")


def test_the_uwb_listed_in_the_options_ranges_to_the_worlds_own_anchors():
    cfg = load_config()
    options = TwinOptions(world="aisles", start_xy_yaw=None, visuals=False, sensors=("uwb",))
    twin = Twin(cfg, options)
    ranges = []
    twin.on_message(lambda _topic, msg, _t: ranges.append(msg), topics=("uwb/range",))
    twin.advance(0.5)
    uwb = twin.sensors["uwb"]
    world = uwb_anchors_xy_m("aisles")
    assert world is not None and not np.array_equal(world, cfg.uwb.anchors_xy_m)
    np.testing.assert_array_equal(uwb.anchors_xyz_m[:, :2], world)
    assert len(ranges) >= 0.5 * cfg.uwb.rate_hz * 0.5 * len(world)  # some exchanges lost


def test_in_a_world_without_anchors_the_uwb_takes_the_configured_ones():
    cfg = load_config()
    twin = Twin(cfg, TwinOptions(world="empty", visuals=False, sensors=("uwb",)))
    np.testing.assert_array_equal(twin.sensors["uwb"].anchors_xyz_m[:, :2], cfg.uwb.anchors_xy_m)
