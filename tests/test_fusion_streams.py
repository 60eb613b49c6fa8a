"""SE(2) algebra and stamp-ordered replay of the fusion experiment's streams (no mujoco)."""

import math

import numpy as np
import pytest

from amr_twin.experiments.fusion_streams import (Streams, interpolate_pose, relative_motion, se2_between,
                                                 se2_compose, wrap_rad)
from amr_twin.messages import Header, Odometry, Quaternion, Time


def _odom(t_us: int, x: float, y: float, yaw: float) -> Odometry:
    msg = Odometry(header=Header(0, Time.from_us(t_us), "odom"), child_frame_id="base_link")
    msg.pose.pose.position.x, msg.pose.pose.position.y = x, y
    msg.pose.pose.orientation = Quaternion.from_yaw(yaw)
    return msg


def test_compose_then_between_is_identity():
    rng = np.random.default_rng(1)
    a = rng.uniform([-5, -5, -math.pi], [5, 5, math.pi], size=(50, 3))
    b = rng.uniform([-5, -5, -math.pi], [5, 5, math.pi], size=(50, 3))
    np.testing.assert_allclose(se2_between(a, se2_compose(a, b)), b, atol=1e-12)


def test_compose_known_case():
    # a point 1 m ahead of a robot at (2, 3) facing +y is at (2, 4)
    np.testing.assert_allclose(se2_compose([2.0, 3.0, math.pi / 2], [1.0, 0.0, 0.0]), [2.0, 4.0, math.pi / 2],
                               atol=1e-12)


def test_wrap_and_interpolation_across_pi():
    assert wrap_rad(3 * math.pi / 2) == pytest.approx(-math.pi / 2)
    t = np.array([0.0, 1.0])
    pose = np.array([[0.0, 0.0, math.pi - 0.1], [1.0, 0.0, -math.pi + 0.1]])
    mid = interpolate_pose(t, pose, 0.5)
    assert abs(abs(mid[2]) - math.pi) < 1e-9  # through pi, not through 0
    assert mid[0] == pytest.approx(0.5)


def test_relative_motion_in_body_frame():
    t = np.array([0.0, 1.0])
    pose = np.array([[1.0, 1.0, math.pi / 2], [1.0, 2.0, math.pi / 2]])  # 1 m along its own x (world +y)
    dx, dy, dyaw = relative_motion(t, pose, 0.0, 1.0)
    assert (dx, dy, dyaw) == pytest.approx((1.0, 0.0, 0.0), abs=1e-12)


def test_tap_keeps_topics_and_merged_is_stamp_ordered():
    s = Streams()
    s.tap("odom", _odom(30_000, 0, 0, 0), 30_000)
    s.tap("odom", _odom(10_000, 0, 0, 0), 31_000)   # published late, stamped early
    s.tap("wheel0_Vel", object(), 0)                 # not a recorded topic
    imu_like = _odom(20_000, 0, 0, 0)
    s.tap("imu/data_raw", imu_like, 20_000)
    assert s.counts() == {"odom": 2, "imu": 1, "uwb": 0, "scan": 0}
    stamps = [m.header.stamp.to_us() for _k, m in s.merged(("odom", "imu"))]
    assert sorted(stamps) == [10_000, 20_000, 30_000]
    kinds = [k for k, _m in s.merged(("imu",))]
    assert kinds == ["imu"]
