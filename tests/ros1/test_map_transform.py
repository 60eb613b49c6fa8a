"""``map -> odom`` from the localisation's pose in ``map`` and the odometry
(amr_twin/ros1/map_transform.py): composed with ``odom -> base_link`` it gives the localisation's
pose, at 25 Hz of stamps, in genpy's bytes. The graph's side (tf2_ros resolving ``map -> base_link``
on a real master) is in ``test_move_base.py``."""

import io
import math

import numpy as np
import pytest

from conftest import needs_ros1
from amr_twin.ros.geometry_messages import Odometry, Point, Pose, PoseWithCovariance, Quaternion
from amr_twin.ros.messages import Header, Time
from amr_twin.ros1.map_transform import MapTransform


def _odometry(t_us: int, frame: str, x: float, y: float, yaw: float) -> Odometry:
    return Odometry(
        Header(0, Time.from_us(t_us), frame),
        "base_link",
        PoseWithCovariance(Pose(Point(x, y, 0.0), Quaternion.from_yaw(yaw))),
    )


def _decode(data: bytes) -> tuple:
    """(sec, nsec, parent, child, x, y, yaw) of a one-transform TFMessage."""
    import struct

    count, _seq, sec, nsec, n = struct.unpack_from("<IIIII", data)
    parent = data[20 : 20 + n].decode()
    (m,) = struct.unpack_from("<I", data, 20 + n)
    child = data[24 + n : 24 + n + m].decode()
    x, y, _z, qx, qy, qz, qw = struct.unpack_from("<7d", data, 24 + n + m)
    assert count == 1 and len(data) == 24 + n + m + 56
    return (
        sec,
        nsec,
        parent,
        child,
        x,
        y,
        math.atan2(2 * (qw * qz + qx * qy), 1 - 2 * (qy * qy + qz * qz)),
    )


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_map_to_odom_composed_with_the_odometry_gives_the_map_pose(seed):
    rng = np.random.default_rng(seed)
    tf = MapTransform()
    for k in range(5):
        t_us = 1_000_000 + k * 50_000
        odom = rng.uniform([-20, -20, -math.pi], [20, 20, math.pi])
        pose = rng.uniform([-20, -20, -math.pi], [20, 20, math.pi])
        assert tf.take("odom", _odometry(t_us, "odom", *odom)) is None
        stamp_us, data = tf.take("odometry/filtered", _odometry(t_us, "map", *pose))
        sec, nsec, parent, child, x, y, yaw = _decode(data)
        assert (parent, child, stamp_us, sec * 1_000_000 + nsec // 1000) == (
            "map",
            "odom",
            t_us,
            t_us,
        )
        c, s = math.cos(yaw), math.sin(yaw)
        got = (x + c * odom[0] - s * odom[1], y + s * odom[0] + c * odom[1], yaw + odom[2])
        assert got[:2] == pytest.approx(tuple(pose[:2]), abs=1e-9)
        assert math.remainder(got[2] - pose[2], math.tau) == pytest.approx(0.0, abs=1e-9)


def test_twenty_five_a_second_from_the_first_map_source_only():
    """50 Hz EKF poses for 2 s: 50 messages; the ground truth (a second source), a pose in another
    frame and a pose before any odometry give none."""
    tf = MapTransform()
    assert (
        tf.take("odometry/filtered", _odometry(0, "map", 1.0, 2.0, 0.0)) is None
    )  # no odometry yet
    sent = []
    for t_us in range(0, 2_000_000, 20_000):
        tf.take("odom", _odometry(t_us, "odom", t_us * 1e-6, 0.0, 0.0))
        assert (
            tf.take("odometry/filtered", _odometry(t_us, "odom", 0.0, 0.0, 0.0)) is None
        )  # not in map
        if t_us:  # the EKF published first: the ground truth is left out
            assert tf.take("ground_truth/odom", _odometry(t_us, "map", 5.0, 5.0, 0.0)) is None
        got = tf.take("odometry/filtered", _odometry(t_us, "map", 1.0, 2.0, 0.5))
        if got is not None:
            sent.append(got[0])
    assert len(sent) == 50 == tf.sent and tf.source == "odometry/filtered"
    assert np.all(np.diff(sent) == 40_000)


@needs_ros1
def test_the_bytes_are_genpys():
    from amr_twin.ros1.messages import Ros1Messages

    Ros1Messages()  # puts Debian's packages on the path
    from geometry_msgs.msg import TransformStamped
    from tf2_msgs.msg import TFMessage
    import rospy

    tf = MapTransform()
    tf.take("odom", _odometry(0, "odom", 0.3, -0.2, 0.4))
    stamp_us, data = tf.take("ground_truth/odom", _odometry(1_230_000, "map", 4.0, 1.0, -2.0))
    _sec, _nsec, _parent, _child, x, y, yaw = _decode(data)
    ts = TransformStamped()
    ts.header.stamp, ts.header.frame_id, ts.child_frame_id = (
        rospy.Time(1, 230_000_000),
        "map",
        "odom",
    )
    ts.transform.translation.x, ts.transform.translation.y = x, y
    ts.transform.rotation.z, ts.transform.rotation.w = math.sin(yaw / 2), math.cos(yaw / 2)
    buf = io.BytesIO()
    TFMessage(transforms=[ts]).serialize(buf)
    assert buf.getvalue() == data and stamp_us == 1_230_000
