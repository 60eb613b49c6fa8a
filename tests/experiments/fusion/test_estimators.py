"""The fusion experiment's estimates of recorded streams: odometry in the map, the EKF replay, the
last pose per stamp."""

import math

import numpy as np
import pytest

from amr_twin.experiments.fusion.estimators import (
    estimate_ekf,
    estimate_odom,
    laser_in_base,
    last_per_stamp,
)
from amr_twin.experiments.fusion.streams import Streams
from amr_twin.model.config import load_config
from amr_twin.ros.geometry_messages import Odometry, Point, Pose, PoseWithCovariance, Quaternion
from amr_twin.ros.messages import Header, Time


def _odom(t_us: int, x_m: float, yaw_rad: float) -> Odometry:
    pose = Pose(Point(x_m, 0.0, 0.0), Quaternion.from_yaw(yaw_rad))
    return Odometry(
        header=Header(0, Time.from_us(t_us), "odom"),
        child_frame_id="base_link",
        pose=PoseWithCovariance(pose, [0.0] * 36),
    )


def test_last_per_stamp_keeps_the_last_pose_of_each_instant():
    t = np.array([0.0, 0.0, 0.1, 0.2, 0.2])
    pose = np.arange(15.0).reshape(5, 3)
    t_kept, pose_kept = last_per_stamp(t, pose)
    assert t_kept.tolist() == [0.0, 0.1, 0.2]
    assert pose_kept[:, 0].tolist() == [3.0, 6.0, 12.0]


def test_the_odometry_is_moved_into_the_map_by_the_start_pose():
    streams = Streams(odom=[_odom(0, 0.0, 0.0), _odom(100_000, 1.0, 0.0)])
    est = estimate_odom(streams, (2.0, 1.0, math.pi / 2))
    assert est.name == "odom"
    assert est.t_s.tolist() == pytest.approx([0.0, 0.1])
    assert est.pose[-1] == pytest.approx([2.0, 2.0, math.pi / 2])


def test_the_ekf_replay_starts_at_the_start_pose_and_names_its_inputs():
    cfg = load_config()
    streams = Streams(odom=[_odom(k * 10_000, 0.0, 0.0) for k in range(20)])
    est = estimate_ekf(cfg, streams, (1.0, -1.0, 0.5), use_imu=True, use_uwb=False)
    assert est.name == "odom+imu"
    assert len(est.t_s) == 20
    assert est.pose[-1] == pytest.approx([1.0, -1.0, 0.5], abs=1e-6)


def test_the_laser_sits_where_the_lidar_is_mounted():
    cfg = load_config()
    x, y, yaw = laser_in_base(cfg)
    assert (x, y, yaw) == (cfg.components.lidar.pos_m[0], cfg.components.lidar.pos_m[1], 0.0)
