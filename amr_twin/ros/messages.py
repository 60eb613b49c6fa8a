"""ROS 1 message types used by the twin, as plain slotted dataclasses.

Names, field names and field order follow the ROS message definitions. Each class
has a ``_type`` (``"package/Name"``) and ``serialized_size()``, the byte count of
its ROS 1 serialisation (strings and variable arrays prefixed by a uint32 length),
which the rosserial link turns into UART time. Stamps are :class:`Time`
``(sec, nanosec)`` of simulation time, exact from the clock's microseconds
(:meth:`Time.from_us`; ROS 1 names the fields ``secs``/``nsecs``). Covariances are
float64 arrays (row-major 6x6 or 3x3), ``LaserScan`` ranges/intensities float32
arrays; classes holding arrays compare by identity (``eq=False``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import ClassVar

import numpy as np


def _string_size(text: str) -> int:
    """Serialised size of a ROS string: uint32 length + UTF-8 bytes."""
    return 4 + len(text.encode("utf-8"))


class _Fixed:
    """Base of the message types whose serialisation has a fixed size ``_SIZE``."""

    __slots__ = ()
    _SIZE: ClassVar[int] = 0

    def serialized_size(self) -> int:
        return self._SIZE


def _zeros(n: int):
    return lambda: np.zeros(n, dtype=np.float64)


@dataclass(slots=True, frozen=True)
class Time:
    """A ROS time stamp: whole seconds and nanoseconds (0 <= nanosec < 1e9)."""

    sec: int = 0
    nanosec: int = 0

    @classmethod
    def from_us(cls, t_us: int) -> Time:
        """Exact stamp of an integer number of microseconds.

        Made through the slots directly (a frozen dataclass's ``__init__`` sets each field
        with ``object.__setattr__``: twice the cost); every published message is stamped."""
        sec, rem_us = divmod(int(t_us), 1_000_000)
        if cls is not Time:
            return cls(sec, rem_us * 1000)
        stamp = _new_object(Time)
        _set_sec(stamp, sec)
        _set_nanosec(stamp, rem_us * 1000)
        return stamp

    @classmethod
    def from_sec(cls, t_s: float) -> Time:
        """Stamp of a time in seconds, rounded to the nearest nanosecond."""
        sec, nanosec = divmod(int(round(t_s * 1e9)), 1_000_000_000)
        return cls(sec, nanosec)

    def to_sec(self) -> float:
        """Time in seconds."""
        return self.sec + self.nanosec * 1e-9

    def to_us(self) -> int:
        """Time in whole microseconds (truncated)."""
        return self.sec * 1_000_000 + self.nanosec // 1000


_new_object = object.__new__
_set_sec, _set_nanosec = Time.__dict__["sec"].__set__, Time.__dict__["nanosec"].__set__


# -- std_msgs -----------------------------------------------------------------
@dataclass(slots=True)
class Header:
    """std_msgs/Header: sequence number, stamp (sim time), coordinate frame."""

    _type: ClassVar[str] = "std_msgs/Header"
    seq: int = 0
    stamp: Time = field(default_factory=Time)
    frame_id: str = ""

    def serialized_size(self) -> int:
        return 4 + 8 + _string_size(self.frame_id)


@dataclass(slots=True)
class Float64(_Fixed):
    """std_msgs/Float64."""

    _type: ClassVar[str] = "std_msgs/Float64"
    _SIZE: ClassVar[int] = 8
    data: float = 0.0


@dataclass(slots=True)
class MultiArrayDimension:
    """std_msgs/MultiArrayDimension."""

    _type: ClassVar[str] = "std_msgs/MultiArrayDimension"
    label: str = ""
    size: int = 0
    stride: int = 0

    def serialized_size(self) -> int:
        return _string_size(self.label) + 8


@dataclass(slots=True)
class MultiArrayLayout:
    """std_msgs/MultiArrayLayout (the thesis leaves ``dim`` empty, fig. 3.3)."""

    _type: ClassVar[str] = "std_msgs/MultiArrayLayout"
    dim: list[MultiArrayDimension] = field(default_factory=list)
    data_offset: int = 0

    def serialized_size(self) -> int:
        return 4 + sum(d.serialized_size() for d in self.dim) + 4


@dataclass(slots=True)
class Float64MultiArray:
    """std_msgs/Float64MultiArray."""

    _type: ClassVar[str] = "std_msgs/Float64MultiArray"
    layout: MultiArrayLayout = field(default_factory=MultiArrayLayout)
    data: list[float] = field(default_factory=list)

    def serialized_size(self) -> int:
        return self.layout.serialized_size() + 4 + 8 * len(self.data)


@dataclass(slots=True)
class String:
    """std_msgs/String."""

    _type: ClassVar[str] = "std_msgs/String"
    data: str = ""

    def serialized_size(self) -> int:
        return _string_size(self.data)


@dataclass(slots=True)
class Clock(_Fixed):
    """rosgraph_msgs/Clock: the simulation time (``/clock``, ``use_sim_time``)."""

    _type: ClassVar[str] = "rosgraph_msgs/Clock"
    _SIZE: ClassVar[int] = 8
    clock: Time = field(default_factory=Time)


# -- geometry_msgs --------------------------------------------------------------
@dataclass(slots=True)
class Vector3(_Fixed):
    """geometry_msgs/Vector3."""

    _type: ClassVar[str] = "geometry_msgs/Vector3"
    _SIZE: ClassVar[int] = 24
    x: float = 0.0
    y: float = 0.0
    z: float = 0.0


@dataclass(slots=True)
class Point(_Fixed):
    """geometry_msgs/Point, metres."""

    _type: ClassVar[str] = "geometry_msgs/Point"
    _SIZE: ClassVar[int] = 24
    x: float = 0.0
    y: float = 0.0
    z: float = 0.0


@dataclass(slots=True)
class Quaternion(_Fixed):
    """geometry_msgs/Quaternion (x, y, z, w); the default is the identity."""

    _type: ClassVar[str] = "geometry_msgs/Quaternion"
    _SIZE: ClassVar[int] = 32
    x: float = 0.0
    y: float = 0.0
    z: float = 0.0
    w: float = 1.0

    @classmethod
    def from_yaw(cls, yaw_rad: float) -> Quaternion:
        """Rotation of ``yaw_rad`` about +z (REP-103: counter-clockwise positive)."""
        return cls(0.0, 0.0, math.sin(0.5 * yaw_rad), math.cos(0.5 * yaw_rad))

    def yaw_rad(self) -> float:
        """Heading about +z in (-pi, pi], radians."""
        return math.atan2(2.0 * (self.w * self.z + self.x * self.y),
                          1.0 - 2.0 * (self.y * self.y + self.z * self.z))


@dataclass(slots=True)
class Pose(_Fixed):
    """geometry_msgs/Pose."""

    _type: ClassVar[str] = "geometry_msgs/Pose"
    _SIZE: ClassVar[int] = 56
    position: Point = field(default_factory=Point)
    orientation: Quaternion = field(default_factory=Quaternion)


@dataclass(slots=True, eq=False)
class PoseWithCovariance(_Fixed):
    """geometry_msgs/PoseWithCovariance; covariance of (x, y, z, rx, ry, rz), 36 values."""

    _type: ClassVar[str] = "geometry_msgs/PoseWithCovariance"
    _SIZE: ClassVar[int] = 56 + 36 * 8
    pose: Pose = field(default_factory=Pose)
    covariance: np.ndarray = field(default_factory=_zeros(36))


@dataclass(slots=True)
class Twist(_Fixed):
    """geometry_msgs/Twist: linear (m/s) and angular (rad/s) velocity."""

    _type: ClassVar[str] = "geometry_msgs/Twist"
    _SIZE: ClassVar[int] = 48
    linear: Vector3 = field(default_factory=Vector3)
    angular: Vector3 = field(default_factory=Vector3)


@dataclass(slots=True, eq=False)
class TwistWithCovariance(_Fixed):
    """geometry_msgs/TwistWithCovariance; 36 covariance values."""

    _type: ClassVar[str] = "geometry_msgs/TwistWithCovariance"
    _SIZE: ClassVar[int] = 48 + 36 * 8
    twist: Twist = field(default_factory=Twist)
    covariance: np.ndarray = field(default_factory=_zeros(36))


@dataclass(slots=True)
class Transform(_Fixed):
    """geometry_msgs/Transform: translation (m) and rotation."""

    _type: ClassVar[str] = "geometry_msgs/Transform"
    _SIZE: ClassVar[int] = 56
    translation: Vector3 = field(default_factory=Vector3)
    rotation: Quaternion = field(default_factory=Quaternion)


@dataclass(slots=True)
class TransformStamped:
    """geometry_msgs/TransformStamped: pose of ``child_frame_id`` in ``header.frame_id``."""

    _type: ClassVar[str] = "geometry_msgs/TransformStamped"
    header: Header = field(default_factory=Header)
    child_frame_id: str = ""
    transform: Transform = field(default_factory=Transform)

    def serialized_size(self) -> int:
        return self.header.serialized_size() + _string_size(self.child_frame_id) + 56


@dataclass(slots=True)
class TFMessage:
    """tf2_msgs/TFMessage."""

    _type: ClassVar[str] = "tf2_msgs/TFMessage"
    transforms: list[TransformStamped] = field(default_factory=list)

    def serialized_size(self) -> int:
        return 4 + sum(t.serialized_size() for t in self.transforms)


# -- sensor_msgs ----------------------------------------------------------------
@dataclass(slots=True, eq=False)
class Imu:
    """sensor_msgs/Imu. A covariance whose element 0 is -1 means "not provided"."""

    _type: ClassVar[str] = "sensor_msgs/Imu"
    header: Header = field(default_factory=Header)
    orientation: Quaternion = field(default_factory=Quaternion)
    orientation_covariance: np.ndarray = field(default_factory=_zeros(9))
    angular_velocity: Vector3 = field(default_factory=Vector3)
    angular_velocity_covariance: np.ndarray = field(default_factory=_zeros(9))
    linear_acceleration: Vector3 = field(default_factory=Vector3)
    linear_acceleration_covariance: np.ndarray = field(default_factory=_zeros(9))

    def serialized_size(self) -> int:
        return self.header.serialized_size() + 32 + 24 + 24 + 3 * 72


@dataclass(slots=True, eq=False)
class MagneticField:
    """sensor_msgs/MagneticField, tesla."""

    _type: ClassVar[str] = "sensor_msgs/MagneticField"
    header: Header = field(default_factory=Header)
    magnetic_field: Vector3 = field(default_factory=Vector3)
    magnetic_field_covariance: np.ndarray = field(default_factory=_zeros(9))

    def serialized_size(self) -> int:
        return self.header.serialized_size() + 24 + 72


@dataclass(slots=True, eq=False)
class LaserScan:
    """sensor_msgs/LaserScan: angles in rad, times in s, ranges in m (float32 on the wire)."""

    _type: ClassVar[str] = "sensor_msgs/LaserScan"
    header: Header = field(default_factory=Header)
    angle_min: float = 0.0
    angle_max: float = 0.0
    angle_increment: float = 0.0
    time_increment: float = 0.0
    scan_time: float = 0.0
    range_min: float = 0.0
    range_max: float = 0.0
    ranges: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=np.float32))
    intensities: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=np.float32))

    def serialized_size(self) -> int:
        return (self.header.serialized_size() + 7 * 4
                + 4 + 4 * len(self.ranges) + 4 + 4 * len(self.intensities))


@dataclass(slots=True, eq=False)
class JointState:
    """sensor_msgs/JointState: per named joint, position (rad or m), velocity (rad/s or m/s), effort.

    The arrays are float64, as long as ``name`` or empty.
    """

    _type: ClassVar[str] = "sensor_msgs/JointState"
    header: Header = field(default_factory=Header)
    name: list[str] = field(default_factory=list)
    position: np.ndarray = field(default_factory=_zeros(0))
    velocity: np.ndarray = field(default_factory=_zeros(0))
    effort: np.ndarray = field(default_factory=_zeros(0))

    def serialized_size(self) -> int:
        return (self.header.serialized_size() + 4 + sum(_string_size(n) for n in self.name)
                + 12 + 8 * (len(self.position) + len(self.velocity) + len(self.effort)))


# -- nav_msgs -------------------------------------------------------------------
@dataclass(slots=True, eq=False)
class Odometry:
    """nav_msgs/Odometry: pose in ``header.frame_id``, twist in ``child_frame_id``."""

    _type: ClassVar[str] = "nav_msgs/Odometry"
    header: Header = field(default_factory=Header)
    child_frame_id: str = ""
    pose: PoseWithCovariance = field(default_factory=PoseWithCovariance)
    twist: TwistWithCovariance = field(default_factory=TwistWithCovariance)

    def serialized_size(self) -> int:
        return (self.header.serialized_size() + _string_size(self.child_frame_id)
                + self.pose.serialized_size() + self.twist.serialized_size())


@dataclass(slots=True)
class Range:
    """sensor_msgs/Range: one distance reading, m; angles in rad.

    ROS defines only ``ULTRASOUND`` (0) and ``INFRARED`` (1) radiation types and has no
    UWB type: the twin's UWB ranges use ``INFRARED`` (1), the nearest (an
    electromagnetic time of flight), with ``field_of_view`` 2 pi (omnidirectional).
    A reading outside ``[min_range, max_range]`` is invalid, as in ROS.
    """

    _type: ClassVar[str] = "sensor_msgs/Range"
    ULTRASOUND: ClassVar[int] = 0
    INFRARED: ClassVar[int] = 1
    header: Header = field(default_factory=Header)
    radiation_type: int = 0
    field_of_view: float = 0.0
    min_range: float = 0.0
    max_range: float = 0.0
    range: float = 0.0

    def serialized_size(self) -> int:
        return self.header.serialized_size() + 1 + 4 * 4
