"""SE(2) algebra and stamp-ordered replay of the fusion experiment's streams (no mujoco)."""

import math

import numpy as np
import pytest

from amr_twin.experiments.fusion.streams import Streams, relative_motion
from amr_twin.ros.geometry_messages import Odometry, Quaternion
from amr_twin.ros.messages import Header, Time


def _odom(t_us: int, x: float, y: float, yaw: float) -> Odometry:
    msg = Odometry(header=Header(0, Time.from_us(t_us), "odom"), child_frame_id="base_link")
    msg.pose.pose.position.x, msg.pose.pose.position.y = x, y
    msg.pose.pose.orientation = Quaternion.from_yaw(yaw)
    return msg


def test_relative_motion_in_body_frame():
    t = np.array([0.0, 1.0])
    pose = np.array(
        [[1.0, 1.0, math.pi / 2], [1.0, 2.0, math.pi / 2]]
    )  # 1 m along its own x (world +y)
    dx, dy, dyaw = relative_motion(t, pose, 0.0, 1.0)
    assert (dx, dy, dyaw) == pytest.approx((1.0, 0.0, 0.0), abs=1e-12)


def test_tap_keeps_topics_and_merged_is_stamp_ordered():
    s = Streams()
    s.tap("odom", _odom(30_000, 0, 0, 0), 30_000)
    s.tap("odom", _odom(10_000, 0, 0, 0), 31_000)  # published late, stamped early
    s.tap("wheel0_Vel", object(), 0)  # not a recorded topic
    imu_like = _odom(20_000, 0, 0, 0)
    s.tap("imu/data_raw", imu_like, 20_000)
    assert s.counts() == {"odom": 2, "imu": 1, "uwb": 0, "scan": 0}
    stamps = [m.header.stamp.to_us() for _k, m in s.merged(("odom", "imu"))]
    assert sorted(stamps) == [10_000, 20_000, 30_000]
    kinds = [k for k, _m in s.merged(("imu",))]
    assert kinds == ["imu"]
