"""The footprint from the model's parameters, and its geometry."""

import math

import numpy as np

from amr_twin.model.config import load_config
from amr_twin.navigation.footprint import robot_footprint


def test_the_footprint_is_the_chassis_with_the_wheels_sticking_out():
    cfg = load_config()
    fp = robot_footprint(cfg)
    assert fp.x_max_m == -fp.x_min_m == cfg.chassis.length_m / 2 == 0.35
    assert math.isclose(
        fp.half_width_m, cfg.wheel.separation_m / 2 + cfg.wheel.width_m / 2
    )  # 0.265 m
    assert math.isclose(fp.inscribed_radius_m, 0.265) and math.isclose(
        fp.circumscribed_radius_m, math.hypot(0.35, 0.265)
    )
    wider = robot_footprint(load_config(sets=["wheel.separation_m=0.485"]))
    assert wider.half_width_m > fp.half_width_m


def test_distance_and_containment():
    fp = robot_footprint(load_config())
    pts = np.array([[0.0, 0.0], [0.35, 0.265], [0.45, 0.0], [0.45, 0.365], [-1.35, 0.0]])
    assert fp.contains(pts).tolist() == [True, True, False, False, False]
    assert np.allclose(fp.distance_m(pts), [0.0, 0.0, 0.1, math.hypot(0.1, 0.1), 1.0])
    assert len(fp.outline_xy_m(0.05)) >= 2 * (0.7 + 0.53) / 0.05
