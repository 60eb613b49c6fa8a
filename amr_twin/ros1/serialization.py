"""The ROS 1 wire format of the twin's high-rate messages, written with ``struct`` (the bridge's
fast path).

Filling genpy's message objects field by field cost 26 us (``sensor_msgs/Imu``) to 38 us
(``nav_msgs/Odometry``) a message, six times their serialisation; these writers produce the same
bytes (``tests/ros1/test_serialization.py`` compares them with genpy's, type by type) in a few
microseconds. The ROS 1 format: little-endian, no alignment; a string or a variable array is a
uint32 count then its items; ``time`` is uint32 sec, uint32 nsec; ``std_msgs/Header`` is uint32 seq,
time, string frame_id.
:data:`WRITERS` maps a type to its writer ``f(msg) -> bytes``; the rest go through genpy.
"""

from __future__ import annotations

import functools
import struct
from typing import Callable

import numpy as np

_I = struct.Struct("<I")
_HEAD = struct.Struct("<III")
_F7 = struct.Struct("<7f")
_F8 = np.dtype("<f8")


@functools.lru_cache(maxsize=1024)
def _string(text: str) -> bytes:
    """A string's bytes (a frame's or a joint's name: a few, written again and again)."""
    data = text.encode()
    return _I.pack(len(data)) + data


def _header(h) -> bytes:
    return _HEAD.pack(h.seq & 0xFFFFFFFF, h.stamp.sec, h.stamp.nanosec) + _string(h.frame_id)


@functools.lru_cache(maxsize=1024)
def _framed(frames: tuple, tail: str) -> tuple[struct.Struct, bytes]:
    """A ``Struct`` of a header's seq and stamp, then the strings ``frames`` (the header's frame_id,
    maybe a child frame's), then ``tail``; and those strings' bytes (a message's fixed part in one
    ``pack``)."""
    blob = b"".join(_string(f) for f in frames)
    return struct.Struct(f"<III{len(blob)}s{tail}"), blob


def _stamped_pose(h, child_frame_id: str, x, q) -> bytes:
    """A header, a child frame, a position and a quaternion: what an ``Odometry`` and
    each ``TransformStamped`` of a ``TFMessage`` share, in one ``pack``."""
    head, blob = _framed((h.frame_id, child_frame_id), "7d")
    return head.pack(
        h.seq & 0xFFFFFFFF, h.stamp.sec, h.stamp.nanosec, blob, x.x, x.y, x.z, q.x, q.y, q.z, q.w
    )


def _f64s(values, count: bool) -> bytes:
    if (
        type(values) is np.ndarray and values.dtype is _F8
    ):  # the twin's covariances and arrays: as they are
        data = values.tobytes()
    else:
        data = np.asarray(values, dtype=_F8).tobytes()
    return (_I.pack(len(data) // 8) + data) if count else data


def _fixed(values, n: int) -> bytes:
    """A ``float64[n]`` (a covariance)'s bytes (ValueError for another count)."""
    if type(values) is np.ndarray and values.dtype is _F8 and values.size == n:
        return values.tobytes()  # the twin's shared covariances: as they are
    data = np.asarray(values, dtype=_F8).tobytes()
    if len(data) != 8 * n:
        raise ValueError(f"a covariance of {n} values has {len(data) // 8}")
    return data


def imu(m) -> bytes:
    h, o, g, a = m.header, m.orientation, m.angular_velocity, m.linear_acceleration
    head, blob = _framed((h.frame_id,), "4d72s3d72s3d72s")
    return head.pack(
        h.seq & 0xFFFFFFFF, h.stamp.sec, h.stamp.nanosec, blob, o.x, o.y, o.z, o.w,
        _fixed(m.orientation_covariance, 9), g.x, g.y, g.z,
        _fixed(m.angular_velocity_covariance, 9), a.x, a.y, a.z,
        _fixed(m.linear_acceleration_covariance, 9),
    )  # fmt: skip


def magnetic_field(m) -> bytes:
    h, v = m.header, m.magnetic_field
    head, blob = _framed((h.frame_id,), "3d72s")
    return head.pack(
        h.seq & 0xFFFFFFFF, h.stamp.sec, h.stamp.nanosec, blob, v.x, v.y, v.z,
        _fixed(m.magnetic_field_covariance, 9),
    )  # fmt: skip


def odometry(m) -> bytes:
    h, p, t = m.header, m.pose.pose, m.twist.twist
    x, q, lin, ang = p.position, p.orientation, t.linear, t.angular
    head, blob = _framed((h.frame_id, m.child_frame_id), "7d288s6d288s")
    return head.pack(
        h.seq & 0xFFFFFFFF, h.stamp.sec, h.stamp.nanosec, blob, x.x, x.y, x.z, q.x, q.y, q.z, q.w,
        _fixed(m.pose.covariance, 36), lin.x, lin.y, lin.z, ang.x, ang.y, ang.z,
        _fixed(m.twist.covariance, 36),
    )  # fmt: skip


def tf_message(m) -> bytes:
    parts = [_I.pack(len(m.transforms))]
    for ts in m.transforms:
        tr = ts.transform
        parts.append(_stamped_pose(ts.header, ts.child_frame_id, tr.translation, tr.rotation))
    return b"".join(parts)


def joint_state(m) -> bytes:
    names = b"".join(_string(n) for n in m.name)
    return b"".join(
        (
            _header(m.header),
            _I.pack(len(m.name)),
            names,
            _f64s(m.position, True),
            _f64s(m.velocity, True),
            _f64s(m.effort, True),
        )
    )


def laser_scan(m) -> bytes:
    ranges = np.asarray(m.ranges, dtype="<f4").tobytes()
    intensities = np.asarray(m.intensities, dtype="<f4").tobytes()
    return b"".join(
        (
            _header(m.header),
            _F7.pack(
                m.angle_min,
                m.angle_max,
                m.angle_increment,
                m.time_increment,
                m.scan_time,
                m.range_min,
                m.range_max,
            ),
            _I.pack(len(ranges) // 4),
            ranges,
            _I.pack(len(intensities) // 4),
            intensities,
        )
    )


def float64_multi_array(m) -> bytes:
    dims = b"".join(_string(d.label) + struct.pack("<II", d.size, d.stride) for d in m.layout.dim)
    return _I.pack(len(m.layout.dim)) + dims + _I.pack(m.layout.data_offset) + _f64s(m.data, True)


def float64(m) -> bytes:
    return struct.pack("<d", m.data)


WRITERS: dict[str, Callable] = {
    "sensor_msgs/Imu": imu,
    "sensor_msgs/MagneticField": magnetic_field,
    "nav_msgs/Odometry": odometry,
    "tf2_msgs/TFMessage": tf_message,
    "sensor_msgs/JointState": joint_state,
    "sensor_msgs/LaserScan": laser_scan,
    "std_msgs/Float64MultiArray": float64_multi_array,
    "std_msgs/Float64": float64,
}
"""ROS type -> writer of the twin's message of that type."""
