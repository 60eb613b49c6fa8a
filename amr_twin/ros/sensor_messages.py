"""sensor_msgs types (ROS 1), as plain slotted dataclasses.

Conventions as in :mod:`amr_twin.ros.messages`: ROS names and field order, ``_type`` and
``serialized_size()`` (ROS 1 bytes), stamps in ``header``. Covariances are row-major 3x3
float64 arrays (9 values), ``LaserScan`` ranges/intensities float32 arrays, ``JointState``
arrays float64; classes holding arrays compare by identity (``eq=False``).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import ClassVar

import numpy as np

from amr_twin.ros.geometry_messages import Quaternion, Vector3
from amr_twin.ros.messages import Header, _string_size, _zeros


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
        return (
            self.header.serialized_size()
            + 7 * 4
            + 4
            + 4 * len(self.ranges)
            + 4
            + 4 * len(self.intensities)
        )


@dataclass(slots=True, eq=False)
class JointState:
    """sensor_msgs/JointState: per named joint, position (rad or m), velocity (rad/s or m/s),
    effort.

    The arrays are float64, as long as ``name`` or empty.
    """

    _type: ClassVar[str] = "sensor_msgs/JointState"
    header: Header = field(default_factory=Header)
    name: list[str] = field(default_factory=list)
    position: np.ndarray = field(default_factory=_zeros(0))
    velocity: np.ndarray = field(default_factory=_zeros(0))
    effort: np.ndarray = field(default_factory=_zeros(0))

    def serialized_size(self) -> int:
        return (
            self.header.serialized_size()
            + 4
            + sum(_string_size(n) for n in self.name)
            + 12
            + 8 * (len(self.position) + len(self.velocity) + len(self.effort))
        )


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
