"""geometry_msgs, tf2_msgs and nav_msgs types (ROS 1), as plain slotted dataclasses.

Conventions as in :mod:`amr_twin.ros.messages`: ROS names and field order, ``_type`` and
``serialized_size()`` (ROS 1 bytes). Positions and translations in m, linear velocity in
m/s, angular velocity in rad/s, quaternions (x, y, z, w); covariances are row-major 6x6
float64 arrays of (x, y, z, rx, ry, rz), 36 values; classes holding arrays compare by
identity (``eq=False``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import ClassVar

import numpy as np

from amr_twin.analysis.se2 import yaw_of_quaternion
from amr_twin.ros.messages import Header, _Fixed, _string_size, _zeros


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
        return yaw_of_quaternion(self.w, self.x, self.y, self.z)


@dataclass(slots=True)
class Pose(_Fixed):
    """geometry_msgs/Pose."""

    _type: ClassVar[str] = "geometry_msgs/Pose"
    _SIZE: ClassVar[int] = 56
    position: Point = field(default_factory=Point)
    orientation: Quaternion = field(default_factory=Quaternion)


@dataclass(slots=True)
class PoseArray:
    """geometry_msgs/PoseArray: poses in ``header.frame_id`` (the twin's ``actors/poses``)."""

    _type: ClassVar[str] = "geometry_msgs/PoseArray"
    header: Header = field(default_factory=Header)
    poses: list[Pose] = field(default_factory=list)

    def serialized_size(self) -> int:
        return self.header.serialized_size() + 4 + 56 * len(self.poses)


@dataclass(slots=True, eq=False)
class PoseWithCovariance(_Fixed):
    """geometry_msgs/PoseWithCovariance; covariance of (x, y, z, rx, ry, rz), 36 values."""

    _type: ClassVar[str] = "geometry_msgs/PoseWithCovariance"
    _SIZE: ClassVar[int] = 56 + 36 * 8
    pose: Pose = field(default_factory=Pose)
    covariance: np.ndarray = field(default_factory=_zeros(36))


@dataclass(slots=True, eq=False)
class PoseWithCovarianceStamped:
    """geometry_msgs/PoseWithCovarianceStamped: a pose estimate in ``header.frame_id`` (AMCL's
    ``amcl_pose``)."""

    _type: ClassVar[str] = "geometry_msgs/PoseWithCovarianceStamped"
    header: Header = field(default_factory=Header)
    pose: PoseWithCovariance = field(default_factory=PoseWithCovariance)

    def serialized_size(self) -> int:
        return self.header.serialized_size() + self.pose.serialized_size()


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
        return (
            self.header.serialized_size()
            + _string_size(self.child_frame_id)
            + self.pose.serialized_size()
            + self.twist.serialized_size()
        )
