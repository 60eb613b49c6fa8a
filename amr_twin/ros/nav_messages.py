"""nav_msgs and geometry_msgs types of the navigation stack (ROS names, plain slotted dataclasses),
and their ROS 2 CDR payloads (XCDR1 little endian, as :mod:`amr_twin.ros.ros2_cdr` writes the
others).

``nav_msgs/Path`` (the plan), ``nav_msgs/OccupancyGrid`` with its ``MapMetaData`` (the map and the
costmaps: ``data`` int8, row-major from the origin cell, 0..100 occupancy or cost, -1 unknown) and
``geometry_msgs/PolygonStamped`` (the footprint, ``Point32`` vertices). Definitions in
:mod:`amr_twin.ros.ros2_schemas`.
"""

from __future__ import annotations

import struct
from dataclasses import dataclass, field
from typing import ClassVar

import numpy as np

from amr_twin.ros.geometry_messages import Pose
from amr_twin.ros.messages import Header, Time
from amr_twin.ros.ros2_cdr import Cdr


@dataclass(slots=True)
class PoseStamped:
    """geometry_msgs/PoseStamped."""

    _type: ClassVar[str] = "geometry_msgs/PoseStamped"
    header: Header = field(default_factory=Header)
    pose: Pose = field(default_factory=Pose)


@dataclass(slots=True, eq=False)
class Path:
    """nav_msgs/Path: poses along a path, each with its own header."""

    _type: ClassVar[str] = "nav_msgs/Path"
    header: Header = field(default_factory=Header)
    poses: list[PoseStamped] = field(default_factory=list)


@dataclass(slots=True)
class MapMetaData:
    """nav_msgs/MapMetaData: cell size (m), size in cells, the pose of cell (0, 0)'s corner."""

    _type: ClassVar[str] = "nav_msgs/MapMetaData"
    map_load_time: Time = field(default_factory=Time)
    resolution: float = 0.0
    width: int = 0
    height: int = 0
    origin: Pose = field(default_factory=Pose)


@dataclass(slots=True, eq=False)
class OccupancyGrid:
    """nav_msgs/OccupancyGrid: ``data`` (height * width) int8, row-major, row 0 at the origin."""

    _type: ClassVar[str] = "nav_msgs/OccupancyGrid"
    header: Header = field(default_factory=Header)
    info: MapMetaData = field(default_factory=MapMetaData)
    data: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int8))


@dataclass(slots=True)
class Point32:
    """geometry_msgs/Point32, float32 m."""

    _type: ClassVar[str] = "geometry_msgs/Point32"
    x: float = 0.0
    y: float = 0.0
    z: float = 0.0


@dataclass(slots=True, eq=False)
class PolygonStamped:
    """geometry_msgs/PolygonStamped (``polygon.points`` as a list of :class:`Point32`)."""

    _type: ClassVar[str] = "geometry_msgs/PolygonStamped"
    header: Header = field(default_factory=Header)
    points: list[Point32] = field(default_factory=list)


_POSE = struct.Struct("<7d")


def _pose(c: Cdr, p: Pose) -> None:
    c.f64(
        p.position.x,
        p.position.y,
        p.position.z,
        p.orientation.x,
        p.orientation.y,
        p.orientation.z,
        p.orientation.w,
    )


def encode_pose_stamped(msg: PoseStamped) -> bytes:
    """The CDR payload of a ``geometry_msgs/PoseStamped``."""
    c = Cdr()
    c.header(msg.header.stamp.sec, msg.header.stamp.nanosec, msg.header.frame_id)
    _pose(c, msg.pose)
    return bytes(c.b)


def encode_path(msg: Path) -> bytes:
    """The CDR payload of a ``nav_msgs/Path``."""
    c = Cdr()
    c.header(msg.header.stamp.sec, msg.header.stamp.nanosec, msg.header.frame_id)
    c.u32(len(msg.poses))
    for ps in msg.poses:
        c.header(ps.header.stamp.sec, ps.header.stamp.nanosec, ps.header.frame_id)
        _pose(c, ps.pose)
    return bytes(c.b)


def encode_occupancy_grid(msg: OccupancyGrid) -> bytes:
    """The CDR payload of a ``nav_msgs/OccupancyGrid``."""
    c = Cdr()
    c.header(msg.header.stamp.sec, msg.header.stamp.nanosec, msg.header.frame_id)
    i = msg.info
    c.stamp(i.map_load_time.sec, i.map_load_time.nanosec)
    c.f32(i.resolution)
    c.u32(i.width)
    c.u32(i.height)
    _pose(c, i.origin)
    data = np.asarray(msg.data, np.int8)
    c.u32(len(data))
    c.b += data.tobytes()
    return bytes(c.b)


def encode_polygon_stamped(msg: PolygonStamped) -> bytes:
    """The CDR payload of a ``geometry_msgs/PolygonStamped``."""
    c = Cdr()
    c.header(msg.header.stamp.sec, msg.header.stamp.nanosec, msg.header.frame_id)
    c.u32(len(msg.points))
    for p in msg.points:
        c.f32(p.x, p.y, p.z)
    return bytes(c.b)
