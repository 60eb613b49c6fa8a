"""UWB ranging: offline ranges, frames, seeds (pure), and the tag in the twin (the error model:
test_uwb_errors.py)."""

import math

import numpy as np
import pytest

from amr_twin.model.config import load_config
from amr_twin.ros.sensor_messages import Range
from amr_twin.sensors.uwb import (
    anchor_frame,
    anchor_index,
    simulate_ranges,
    tag_positions_m,
)


def _cfg(**values):
    return load_config(overrides={f"uwb.{k}": v for k, v in values.items()}).uwb


def test_anchors_from_config_are_inside_the_warehouse():
    cfg = load_config().uwb
    xy = cfg.anchors_xy_m
    assert xy.shape == (4, 2)
    assert np.all(np.abs(xy[:, 0]) < 10.0) and np.all(np.abs(xy[:, 1]) < 7.0)


def test_simulated_ranges_match_the_3d_distance():
    cfg = _cfg(nlos_prob=0.0, dropout_prob=0.0)
    anchors = cfg.anchors_xy_m
    t = np.arange(200) * 0.025
    tag = np.column_stack((np.linspace(-3, 3, 200), np.linspace(1, -1, 200)))
    msgs = simulate_ranges(
        t, tag, anchors, cfg, np.random.default_rng(2), anchor=np.arange(200) % 4
    )
    assert len(msgs) == 200
    dz = cfg.anchor_z_m - cfg.tag_pos_m[2]
    err = []
    for k, m in enumerate(msgs):
        assert isinstance(m, Range) and m.radiation_type == Range.INFRARED
        assert (
            m.header.frame_id == f"uwb_anchor_{k % 4}"
            and m.header.stamp.to_sec() == pytest.approx(t[k])
        )
        assert m.max_range == cfg.max_range_m and m.field_of_view == pytest.approx(2 * math.pi)
        ax, ay = anchors[k % 4]
        err.append(m.range - math.sqrt((tag[k, 0] - ax) ** 2 + (tag[k, 1] - ay) ** 2 + dz * dz))
    assert abs(np.mean(err)) < 0.015 and 0.035 < np.std(err) < 0.065


def test_every_anchor_at_every_time_by_default_and_dropouts_are_absent():
    cfg = _cfg(dropout_prob=0.5)
    msgs = simulate_ranges(
        np.arange(100) * 0.1, np.zeros((100, 2)), cfg.anchors_xy_m, cfg, np.random.default_rng(3)
    )
    assert 150 < len(msgs) < 250  # 400 exchanges, half dropped
    stamps = [m.header.stamp.to_sec() for m in msgs]
    assert stamps == sorted(stamps)


def test_same_seed_same_ranges():
    cfg = load_config().uwb
    t, tag = np.arange(50) * 0.1, np.ones((50, 2))
    a, b, c = (
        simulate_ranges(t, tag, cfg.anchors_xy_m, cfg, np.random.default_rng(s)) for s in (7, 7, 8)
    )
    assert [m.range for m in a] == [m.range for m in b]
    assert [m.range for m in a] != [m.range for m in c]


def test_tag_lever_arm_turns_with_the_robot():
    xy = tag_positions_m(np.array([[1.0, 2.0, 0.0], [1.0, 2.0, math.pi / 2]]), (-0.3, 0.1, 0.45))
    assert xy[0] == pytest.approx([0.7, 2.1])
    assert xy[1] == pytest.approx([0.9, 1.7])


def test_anchor_frames_round_trip_and_bad_frames_are_named():
    assert anchor_index(anchor_frame(3)) == 3
    with pytest.raises(ValueError, match="header.frame_id"):
        anchor_index("laser")


def test_bad_input_is_refused():
    cfg = load_config().uwb
    with pytest.raises(ValueError, match="tag_xy_m"):
        simulate_ranges(
            np.zeros(3), np.zeros((2, 2)), cfg.anchors_xy_m, cfg, np.random.default_rng(0)
        )
    with pytest.raises(ValueError, match="anchor"):
        simulate_ranges(
            np.zeros(2),
            np.zeros((2, 2)),
            cfg.anchors_xy_m,
            cfg,
            np.random.default_rng(0),
            anchor=np.array([0, 4]),
        )


def test_uwb_sensor_in_the_twin():
    from amr_twin.assembly.twin import Twin, TwinOptions
    from amr_twin.sensors.uwb import UwbSensor

    cfg = load_config(overrides={"uwb.nlos_prob": 0.0})
    twin = Twin(cfg, TwinOptions(sensors=("imu", "lidar"), world="warehouse"))
    msgs = []
    twin.bus.subscribe("uwb/range", msgs.append)
    uwb = UwbSensor(
        twin.physics, twin.clock, twin.bus, cfg.uwb, seed=[0, 3], walls=False
    )  # line of sight everywhere: the racks' beams are in some lines here
    twin.advance(1.0)
    # 10 Hz x 4 anchors, round-robin every 25 ms, 5 % dropped
    assert uwb.slot_us == 25_000 and uwb.exchanges in (40, 41)
    assert abs(len(msgs) - 0.95 * uwb.exchanges) <= 6
    assert [anchor_index(m.header.frame_id) for m in msgs[:3]] != [0, 0, 0]
    # the robot stands at the origin facing +x: tag at (-0.30, 0, ~0.45) in the world
    tag = uwb.tag_world_m()
    assert tag[:2] == pytest.approx([-0.30, 0.0], abs=0.01) and abs(tag[2] - 0.45) < 0.03
    true = uwb.true_ranges_m()
    dz = cfg.uwb.anchor_z_m - tag[2]
    assert true[0] == pytest.approx(math.sqrt(9.8**2 + 6.5**2 + dz**2), abs=0.01)
    err = np.array([m.range - true[anchor_index(m.header.frame_id)] for m in msgs])
    assert np.all(np.abs(err) < 4 * cfg.uwb.range_noise_sigma_m)
    assert np.std(err) > 0.02  # noisy, not exact


def test_walls_block_the_bays_anchors_in_the_corridor():
    """Physical NLOS: deep in the corridor world only the end anchor is in sight; the others read
    long."""
    from amr_twin.experiments.fusion.experiment import site_config
    from amr_twin.controllers.route import Route
    from amr_twin.assembly.twin import Twin, TwinOptions
    from amr_twin.sensors.uwb import UwbSensor

    route = Route("here", (28.0, 0.0, 0.0), [[30.0, 0.0]], world="corridor")
    cfg = site_config(load_config(overrides={"uwb.nlos_prob": 0.0, "uwb.dropout_prob": 0.0}), route)
    assert len(cfg.uwb.anchors_x_m) == 5  # the world's own anchors
    twin = Twin(cfg, TwinOptions(world="corridor", start_xy_yaw=route.start_xy_yaw))
    msgs = []
    twin.bus.subscribe("uwb/range", msgs.append)
    uwb = UwbSensor(twin.physics, twin.clock, twin.bus, cfg.uwb, seed=[0, 3])
    twin.advance(3.0)
    per_anchor = np.bincount(np.arange(uwb.exchanges) % 5, minlength=5)  # round-robin from anchor 0
    assert list(uwb.blocked[:4]) == list(per_anchor[:4]) and uwb.blocked[4] == 0
    per_anchor = per_anchor[0]
    true = uwb.true_ranges_m()
    err = {
        i: np.array([m.range - true[i] for m in msgs if anchor_index(m.header.frame_id) == i])
        for i in range(5)
    }
    assert np.all(np.abs(err[4]) < 4 * cfg.uwb.range_noise_sigma_m)  # the end anchor: line of sight
    hall = np.concatenate([err[i] for i in range(4)])
    assert 0.3 < np.mean(hall) < 1.0  # biased long by the walls (mean blocked_bias_m 0.6 m)
    assert len(hall) < 0.85 * 4 * per_anchor  # and often lost (blocked_dropout_prob 0.3)


@pytest.mark.parametrize("robot_2_y, blocked", [(0.0, [1, 0, 0]), (2.0, [0, 0, 0])])
def test_another_robot_blocks_the_line_its_own_body_never(robot_2_y, blocked):
    from amr_twin.base.clock import VirtualClock
    from amr_twin.model.robot_starts import fleet_starts
    from amr_twin.ros.bus import Bus
    from amr_twin.sensors.uwb import UwbSensor
    from amr_twin.sim.settled_physics import settled_fleet

    # anchors at the tag's height: ahead down the aisle past robot 2, behind, and behind again
    cfg = load_config(
        overrides={
            "uwb.anchors_x_m": [3.0, -6.5, -8.0],
            "uwb.anchors_y_m": [0.0, 0.0, 0.0],
            "uwb.anchor_z_m": 0.46,
            "uwb.nlos_prob": 0.0,
        }
    )
    starts = fleet_starts([(-4.0, 0.0, 0.0), (-2.0, robot_2_y, 0.0)])
    fleet = settled_fleet(cfg, "warehouse", starts, True, False, 0.3)
    clock = VirtualClock()
    uwb = UwbSensor(fleet.robots[0], clock, Bus(clock), cfg.uwb, seed=[0, 3])
    clock.run_until(uwb.slot_us * 5)  # two exchanges with each anchor
    assert uwb.exchanges >= 6 and [int(b > 0) for b in uwb.blocked] == blocked
