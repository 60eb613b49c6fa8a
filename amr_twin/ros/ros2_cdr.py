"""CDR payloads of ROS 2 messages (XCDR1 little endian, as rmw / rosbag2 write it).

:class:`Cdr` builds one payload; ``encode_<message>(msg) -> bytes`` serialises one
message of :mod:`amr_twin.ros.messages` (ROS field names) against the definitions of
:mod:`amr_twin.ros.ros2_schemas`. Encoded here with :mod:`struct` and numpy: the generic
encoder of ``mcap-ros2-support`` costs ~3x more. The tests decode the payloads with
``mcap_ros2.decoder`` and with ``rosbags`` (against ROS 2 Humble's own definitions).
"""

from __future__ import annotations

import struct

import numpy as np


class Cdr:
    """Builds one CDR payload: primitives aligned to their size from after the 4-byte header."""

    __slots__ = ("b",)

    def __init__(self):
        self.b = bytearray(b"\x00\x01\x00\x00")

    def _align(self, n: int) -> None:
        pad = -(len(self.b) - 4) % n
        if pad:
            self.b += bytes(pad)

    def u32(self, v: int) -> None:
        self._align(4)
        self.b += _U32.pack(v)

    def u8(self, v: int) -> None:
        self.b.append(v & 0xFF)

    def stamp(self, sec: int, nanosec: int) -> None:
        self._align(4)
        self.b += _STAMP.pack(sec, nanosec)

    def string(self, text: str) -> None:
        data = text.encode("utf-8") + b"\x00"
        self.u32(len(data))
        self.b += data

    def f64(self, *values: float) -> None:
        self._align(8)
        self.b += struct.pack(f"<{len(values)}d", *values)

    def f64_seq(self, values) -> None:  # float64[]
        a = np.asarray(values, "<f8")
        self.u32(len(a))
        if len(a):
            self._align(8)
            self.b += a.tobytes()

    def f32(self, *values: float) -> None:
        self._align(4)
        self.b += struct.pack(f"<{len(values)}f", *values)

    def f32_seq(self, values) -> None:  # float32[]
        a = np.asarray(values, "<f4")
        self.u32(len(a))
        self.b += a.tobytes()

    def header(self, sec: int, nanosec: int, frame_id: str) -> None:
        self.stamp(sec, nanosec)
        self.string(frame_id)


_U32 = struct.Struct("<I")
_STAMP = struct.Struct("<iI")
_F64X3, _F64X4, _F64X6, _F64X7 = (struct.Struct(f"<{n}d") for n in (3, 4, 6, 7))
_ENCAPSULATION = b"\x00\x01\x00\x00"  # CDR little endian, no options
_EMPTY_LAYOUT = _ENCAPSULATION + bytes(8)  # Float64MultiArray: no dimension, data_offset 0
_strings: dict[str, bytes] = {}


def _string(text: str) -> bytes:
    """A CDR string (uint32 length, UTF-8, NUL), cached: frame ids repeat in every message.
    The caller aligns to 4 first."""
    out = _strings.get(text)
    if out is None:
        data = text.encode("utf-8") + b"\x00"
        out = _strings[text] = _U32.pack(len(data)) + data
    return out


def _header(h) -> bytearray:
    """The payload so far: encapsulation, then a ``std_msgs/Header`` at the start of the message."""
    b = bytearray(_ENCAPSULATION)
    b += _STAMP.pack(h.stamp.sec, h.stamp.nanosec)
    b += _string(h.frame_id)
    return b


def _pad(b: bytearray, n: int) -> bytes:
    """Zero bytes that align the next primitive of size ``n`` (offsets count after the
    encapsulation)."""
    return bytes(-(len(b) - 4) % n)


_LE_F64 = np.dtype("<f8")


def _f64_bytes(values) -> bytes:
    """float64 values as little-endian bytes (no length prefix)."""
    if type(values) is np.ndarray and values.dtype == _LE_F64:
        return values.tobytes()
    return np.asarray(values, _LE_F64).tobytes()


def _hdr(c: Cdr, h) -> None:
    """Append the ``std_msgs/Header`` ``h``."""
    c.header(h.stamp.sec, h.stamp.nanosec, h.frame_id)


def encode_odometry(msg) -> bytes:
    """The CDR payload of a ``nav_msgs/Odometry`` message (precompiled: struct layouts, cached
    strings)."""
    b = _header(msg.header)
    b += _pad(b, 4)
    b += _string(msg.child_frame_id)
    b += _pad(b, 8)
    p, o = msg.pose.pose.position, msg.pose.pose.orientation
    lin, ang = msg.twist.twist.linear, msg.twist.twist.angular
    b += _F64X7.pack(p.x, p.y, p.z, o.x, o.y, o.z, o.w)
    b += _f64_bytes(msg.pose.covariance)
    b += _F64X6.pack(lin.x, lin.y, lin.z, ang.x, ang.y, ang.z)
    b += _f64_bytes(msg.twist.covariance)
    return bytes(b)


def encode_tf_message(msg) -> bytes:
    """The CDR payload of a ``tf2_msgs/TFMessage`` message."""
    b = bytearray(_ENCAPSULATION)
    b += _U32.pack(len(msg.transforms))
    for ts in msg.transforms:
        h = ts.header
        b += _STAMP.pack(h.stamp.sec, h.stamp.nanosec)  # 4-aligned: after a u32 or 8-byte doubles
        b += _string(h.frame_id)
        b += _pad(b, 4)
        b += _string(ts.child_frame_id)
        b += _pad(b, 8)
        t, r = ts.transform.translation, ts.transform.rotation
        b += _F64X7.pack(t.x, t.y, t.z, r.x, r.y, r.z, r.w)
    return bytes(b)


def encode_imu(msg) -> bytes:
    """The CDR payload of a ``sensor_msgs/Imu`` message."""
    b = _header(msg.header)
    b += _pad(b, 8)
    o, w, a = msg.orientation, msg.angular_velocity, msg.linear_acceleration
    b += _F64X4.pack(o.x, o.y, o.z, o.w)
    b += _f64_bytes(msg.orientation_covariance)
    b += _F64X3.pack(w.x, w.y, w.z)
    b += _f64_bytes(msg.angular_velocity_covariance)
    b += _F64X3.pack(a.x, a.y, a.z)
    b += _f64_bytes(msg.linear_acceleration_covariance)
    return bytes(b)


def encode_magnetic_field(msg) -> bytes:
    """The CDR payload of a ``sensor_msgs/MagneticField`` message."""
    b = _header(msg.header)
    b += _pad(b, 8)
    f = msg.magnetic_field
    b += _F64X3.pack(f.x, f.y, f.z)
    b += _f64_bytes(msg.magnetic_field_covariance)
    return bytes(b)


def encode_laser_scan(msg) -> bytes:
    """The CDR payload of a ``sensor_msgs/LaserScan`` message."""
    c = Cdr()
    _hdr(c, msg.header)
    c.f32(
        msg.angle_min,
        msg.angle_max,
        msg.angle_increment,
        msg.time_increment,
        msg.scan_time,
        msg.range_min,
        msg.range_max,
    )
    c.f32_seq(msg.ranges)
    c.f32_seq(msg.intensities)
    return bytes(c.b)


def encode_range(msg) -> bytes:
    """The CDR payload of a ``sensor_msgs/Range`` message."""
    c = Cdr()
    _hdr(c, msg.header)
    c.u8(int(msg.radiation_type))
    c.f32(msg.field_of_view, msg.min_range, msg.max_range, msg.range)
    return bytes(c.b)


def encode_battery_state(
    t_ns: int,
    voltage_v: float,
    current_a: float,
    charge_ah: float,
    capacity_ah: float,
    percentage: float,
    frame: str = "base_link",
) -> bytes:
    """The CDR payload of a ``sensor_msgs/BatteryState`` of the lithium pack (in ``frame``).

    ``current_a`` as ROS states it: negative while discharging. Temperature and cell
    values are not modelled (NaN, empty); status discharging, health unknown, Li-ion.
    """
    c = Cdr()
    c.header(t_ns // 1_000_000_000, t_ns % 1_000_000_000, frame)
    c.f32(voltage_v, float("nan"), current_a, charge_ah, capacity_ah, capacity_ah, percentage)
    c.u8(2)  # POWER_SUPPLY_STATUS_DISCHARGING
    c.u8(0)  # POWER_SUPPLY_HEALTH_UNKNOWN
    c.u8(2)  # POWER_SUPPLY_TECHNOLOGY_LION
    c.u8(1)  # present
    c.f32_seq([])
    c.f32_seq([])
    c.string("base")
    c.string("")
    return bytes(c.b)


def encode_float64(msg) -> bytes:
    """The CDR payload of a ``std_msgs/Float64`` message."""
    c = Cdr()
    c.f64(float(msg.data))
    return bytes(c.b)


def encode_float64_multi_array(values, labels: str | None = None) -> bytes:
    """The CDR payload of a ``std_msgs/Float64MultiArray`` of ``values`` (n,).

    Empty layout, or with ``labels`` one dimension of that label, size and stride n.
    """
    if labels is None:  # dim count 0, data_offset 0, n, then the doubles from offset 16
        n = len(values)
        return (
            _EMPTY_LAYOUT + _U32.pack(n) + b"\x00\x00\x00\x00" + _f64_bytes(values)
            if n
            else _EMPTY_LAYOUT + _U32.pack(0)
        )
    c = Cdr()
    c.u32(1)
    c.string(labels)
    c.u32(len(values))
    c.u32(len(values))
    c.u32(0)  # layout.data_offset
    c.f64_seq(values)
    return bytes(c.b)


def encode_float64_multi_array_msg(msg) -> bytes:
    """The CDR payload of a ``std_msgs/Float64MultiArray`` message (its first dimension's label
    kept)."""
    dim = msg.layout.dim
    return encode_float64_multi_array(msg.data, dim[0].label if dim else None)


def encode_string(msg) -> bytes:
    """The CDR payload of a ``std_msgs/String`` message."""
    c = Cdr()
    c.string(msg.data)
    return bytes(c.b)


def encode_clock(msg) -> bytes:
    """The CDR payload of a ``rosgraph_msgs/Clock`` message."""
    return _ENCAPSULATION + _STAMP.pack(msg.clock.sec, msg.clock.nanosec)


def encode_twist(msg) -> bytes:
    """The CDR payload of a ``geometry_msgs/Twist`` message."""
    c = Cdr()
    c.f64(msg.linear.x, msg.linear.y, msg.linear.z, msg.angular.x, msg.angular.y, msg.angular.z)
    return bytes(c.b)


def encode_joint_state(msg) -> bytes:
    """The CDR payload of a ``sensor_msgs/JointState`` message."""
    c = Cdr()
    _hdr(c, msg.header)
    c.u32(len(msg.name))
    for name in msg.name:
        c.string(name)
    c.f64_seq(msg.position)
    c.f64_seq(msg.velocity)
    c.f64_seq(msg.effort)
    return bytes(c.b)


def encode_pose_array(msg) -> bytes:
    """The CDR payload of a ``geometry_msgs/PoseArray`` message."""
    b = _header(msg.header)
    b += _pad(b, 4)
    b += _U32.pack(len(msg.poses))
    if msg.poses:
        b += _pad(b, 8)
    for pose in msg.poses:
        p, o = pose.position, pose.orientation
        b += _F64X7.pack(p.x, p.y, p.z, o.x, o.y, o.z, o.w)
    return bytes(b)


def encode_pose_with_covariance_stamped(msg) -> bytes:
    """The CDR payload of a ``geometry_msgs/PoseWithCovarianceStamped`` message."""
    b = _header(msg.header)
    b += _pad(b, 8)
    p, o = msg.pose.pose.position, msg.pose.pose.orientation
    b += _F64X7.pack(p.x, p.y, p.z, o.x, o.y, o.z, o.w)
    b += _f64_bytes(msg.pose.covariance)
    return bytes(b)
