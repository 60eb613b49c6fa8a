"""The robot's own errors (experiments/fusion/robot.py): drawn per seed, rolled on by the physics,
not by the odometry."""

import math

import numpy as np
import pytest

from amr_twin.model.config import load_config
from amr_twin.experiments.fusion.robot import CLIP_SIGMA, NOMINAL, RobotErrors, draw
from amr_twin.assembly.twin import TwinOptions
from amr_twin.assembly.command import Command
from amr_twin.recording.run import run_command


def test_each_seed_is_another_robot_within_the_sourced_tolerances():
    cfg = load_config()
    w = cfg.wheel
    assert draw(cfg, 3) == draw(cfg, 3) and draw(cfg, 3) != draw(cfg, 4)
    robots = [draw(cfg, s) for s in range(300)]
    radii = np.array([[r.radius_error_left_m, r.radius_error_right_m] for r in robots])
    track = np.array([r.separation_error_m for r in robots])
    hall = np.array([r.hall_misalignment_deg for r in robots])
    assert np.abs(radii).max() <= CLIP_SIGMA * w.radius_tolerance_m
    assert np.std(radii) == pytest.approx(w.radius_tolerance_m, rel=0.15)
    assert np.std(track) == pytest.approx(w.separation_tolerance_m, rel=0.15)
    assert np.std(hall) == pytest.approx(w.hall_misalignment_sigma_deg, rel=0.15)
    assert abs(np.corrcoef(radii.T)[0, 1]) < 0.2  # the two tyres independent
    assert all(r.hall_jitter_us == w.hall_jitter_us for r in robots[:5])


def test_the_errors_go_into_the_physics_and_not_into_the_odometry():
    cfg = load_config()
    robot = RobotErrors(
        radius_error_left_m=-0.0003, radius_error_right_m=0.0004, separation_error_m=0.005
    )
    true = robot.config(cfg)
    assert (
        true.wheel.radius_m == cfg.wheel.radius_m
        and true.wheel.separation_m == cfg.wheel.separation_m
    )
    assert true.wheel.radius_of("left") == pytest.approx(0.1247) and true.wheel.radius_of(
        "right"
    ) == pytest.approx(0.1254)
    from amr_twin.model.build import build

    model = build(true, "empty").model
    left, right = (model.geom(f"amr/wheel_{s}_collision") for s in ("left", "right"))
    assert left.size[0] == pytest.approx(0.1247) and right.size[0] == pytest.approx(0.1254)
    assert model.body("amr/wheel_left_link").pos[1] - model.body("amr/wheel_right_link").pos[
        1
    ] == pytest.approx(0.485)
    assert NOMINAL.config(cfg) == cfg


def _straight(cfg, seconds=8.0):
    res = run_command(
        cfg,
        Command("linear", speed_m_s=0.5),
        seconds,
        TwinOptions(firmware="improved", world="empty"),
    )
    s = res.series
    travelled = float(np.sum(np.hypot(*np.diff(s.pose[:, :2], axis=0).T)))
    return s.pose[-1, 2] - s.pose[0, 2], s.odom[-1, 3] - s.odom[0, 3], travelled


def test_a_bigger_right_tyre_turns_the_robot_left_while_the_odometry_sees_it_straight():
    cfg = load_config()
    robot = RobotErrors(radius_error_right_m=0.0006)  # 3 sigma: 0.48 %
    true_yaw, odom_yaw, travelled = _straight(robot.config(cfg))
    base_true, base_odom, _ = _straight(cfg)
    d = robot.as_dict(cfg)
    expected_rad = (
        math.radians(-d["odom_heading_drift_deg_per_m"]) * travelled
    )  # truth minus odometry
    assert expected_rad > 0.01  # 0.6 mm on one tyre: more than half a degree over the run
    assert (true_yaw - odom_yaw) - (base_true - base_odom) == pytest.approx(expected_rad, rel=0.3)
