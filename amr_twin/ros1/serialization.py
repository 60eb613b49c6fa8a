"""The ROS 1 wire format of the twin's high-rate messages, written with ``struct`` (the bridge's fast path).

Filling genpy's message objects field by field cost 26 us (``sensor_msgs/Imu``) to 38 us
(``nav_msgs/Odometry``) a message, six times their serialisation; these writers produce the same bytes
(``tests/ros1/test_serialization.py`` compares them with genpy's, type by type) in a few microseconds.
The ROS 1 format: little-endian, no alignment; a string or a variable array is a uint32 count then its
items; ``time`` is uint32 sec, uint32 nsec; ``std_msgs/Header`` is uint32 seq, time, string frame_id.
:data:`WRITERS` maps a type to its writer ``f(msg) -> bytes``; the rest go through genpy.
"""

from __future__ import annotations

import struct
from typing import Callable

import numpy as np

_I = struct.Struct("<I")
_HEAD = struct.Struct("<III")
_D3, _D4 = struct.Struct("<3d"), struct.Struct("<4d")
_F7 = struct.Struct("<7f")


def _string(text: str) -> bytes:
    data = text.encode()
    return _I.pack(len(data)) + data


def _header(h) -> bytes:
    return _HEAD.pack(h.seq & 0xFFFFFFFF, h.stamp.sec, h.stamp.nanosec) + _string(h.frame_id)


def _f64s(values, count: bool) -> bytes:
    data = np.asarray(values, dtype="<f8").tobytes()
    return (_I.pack(len(data) // 8) + data) if count else data


def _vec(v) -> bytes:
    return _D3.pack(v.x, v.y, v.z)


def _quat(q) -> bytes:
    return _D4.pack(q.x, q.y, q.z, q.w)


def imu(m) -> bytes:
    return b"".join((_header(m.header), _quat(m.orientation), _f64s(m.orientation_covariance, False),
                     _vec(m.angular_velocity), _f64s(m.angular_velocity_covariance, False),
                     _vec(m.linear_acceleration), _f64s(m.linear_acceleration_covariance, False)))


def magnetic_field(m) -> bytes:
    return _header(m.header) + _vec(m.magnetic_field) + _f64s(m.magnetic_field_covariance, False)


def odometry(m) -> bytes:
    p, t = m.pose.pose, m.twist.twist
    return b"".join((_header(m.header), _string(m.child_frame_id), _vec(p.position), _quat(p.orientation),
                     _f64s(m.pose.covariance, False), _vec(t.linear), _vec(t.angular),
                     _f64s(m.twist.covariance, False)))


def tf_message(m) -> bytes:
    parts = [_I.pack(len(m.transforms))]
    for ts in m.transforms:
        tr = ts.transform
        parts += (_header(ts.header), _string(ts.child_frame_id), _vec(tr.translation), _quat(tr.rotation))
    return b"".join(parts)


def joint_state(m) -> bytes:
    names = b"".join(_string(n) for n in m.name)
    return b"".join((_header(m.header), _I.pack(len(m.name)), names, _f64s(m.position, True),
                     _f64s(m.velocity, True), _f64s(m.effort, True)))


def laser_scan(m) -> bytes:
    ranges = np.asarray(m.ranges, dtype="<f4").tobytes()
    intensities = np.asarray(m.intensities, dtype="<f4").tobytes()
    return b"".join((_header(m.header), _F7.pack(m.angle_min, m.angle_max, m.angle_increment, m.time_increment,
                                                 m.scan_time, m.range_min, m.range_max),
                     _I.pack(len(ranges) // 4), ranges, _I.pack(len(intensities) // 4), intensities))


def float64_multi_array(m) -> bytes:
    dims = b"".join(_string(d.label) + struct.pack("<II", d.size, d.stride) for d in m.layout.dim)
    return _I.pack(len(m.layout.dim)) + dims + _I.pack(m.layout.data_offset) + _f64s(m.data, True)


_ROWS: dict[int, struct.Struct] = {}


def float64_row(values) -> bytes:
    """``std_msgs/Float64MultiArray`` of ``values`` (floats) with no dimensions: what :func:`float64_multi_array`
    gives for ``Float64MultiArray(data=values)``, in one ``struct`` call."""
    n = len(values)
    packer = _ROWS.get(n)
    if packer is None:
        packer = _ROWS[n] = struct.Struct(f"<III{n}d")
    return packer.pack(0, 0, n, *values)


def float64(m) -> bytes:
    return struct.pack("<d", m.data)


_TIME = struct.Struct("<II")


def clock_us(t_us: int) -> bytes:
    """``rosgraph_msgs/Clock`` at ``t_us`` (simulated us)."""
    return _TIME.pack(t_us // 1_000_000, t_us % 1_000_000 * 1000)


class StateFrames:
    """``sensor_msgs/JointState``, the moving links' ``tf2_msgs/TFMessage`` and the ground truth's ``nav_msgs/Odometry``
    written straight from a grid sample's values (one ``struct`` call each, no message objects): the bytes
    :func:`joint_state`, :func:`tf_message` and :func:`odometry` give for :func:`amr_twin.ros.ros_state.joint_state`,
    ``link_transforms`` and ``ground_truth``."""

    def __init__(self, joint_names, child_frames, parent: str, world: str = "world"):
        n = len(joint_names)
        names = b"".join(_string(name) for name in joint_names)
        self._names, self._n = names, n
        self._js = struct.Struct(f"<IIIII{len(names)}sI{n}dI{n}dI")
        self._links = [_string(parent) + _string(child) for child in child_frames]
        self._tf = struct.Struct("<I" + "".join(f"III{len(b)}s7d" for b in self._links))
        frames = _string(world) + _string(parent)
        zeros = bytes(36 * 8)
        self._gt = struct.Struct(f"<III{len(frames)}s7d{len(zeros)}s6d{len(zeros)}s")
        self._gt_frames, self._zeros = frames, zeros

    def joint_state(self, t_us: int, q, qd) -> bytes:
        """Positions ``q`` and velocities ``qd`` (n,) at ``t_us``; no efforts."""
        n, sec, nsec = self._n, t_us // 1_000_000, t_us % 1_000_000 * 1000
        return self._js.pack(0, sec, nsec, 0, n, self._names, n, *q, n, *qd, 0)

    def link_transforms(self, t_us: int, link_pos, link_quat) -> bytes:
        """Each link's position (3,) and orientation (4,) w, x, y, z relative to the parent, at ``t_us``."""
        sec, nsec = t_us // 1_000_000, t_us % 1_000_000 * 1000
        args = [len(self._links)]
        for blob, (x, y, z), (w, qx, qy, qz) in zip(self._links, link_pos, link_quat):
            args += (0, sec, nsec, blob, x, y, z, qx, qy, qz, w)
        return self._tf.pack(*args)

    def ground_truth(self, t_us: int, pos, quat, v_body, w_body) -> bytes:
        """``nav_msgs/Odometry`` of the true pose, ``world -> base_link``: position (3,), orientation (4,) w, x, y, z,
        the twist in ``base_link`` (3,) and (3,), zero covariances (:func:`amr_twin.ros.ros_state.ground_truth`)."""
        (x, y, z), (w, qx, qy, qz), zeros = pos, quat, self._zeros
        return self._gt.pack(0, t_us // 1_000_000, t_us % 1_000_000 * 1000, self._gt_frames, x, y, z, qx, qy, qz, w,
                             zeros, *v_body, *w_body, zeros)


WRITERS: dict[str, Callable] = {
    "sensor_msgs/Imu": imu, "sensor_msgs/MagneticField": magnetic_field, "nav_msgs/Odometry": odometry,
    "tf2_msgs/TFMessage": tf_message, "sensor_msgs/JointState": joint_state, "sensor_msgs/LaserScan": laser_scan,
    "std_msgs/Float64MultiArray": float64_multi_array, "std_msgs/Float64": float64,
}
"""ROS type -> writer of the twin's message of that type."""
