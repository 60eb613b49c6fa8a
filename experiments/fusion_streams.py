"""Recorded sensor streams of a drive, and the SE(2) algebra the estimators' replay needs.

A :class:`Streams` is a bus tap: it keeps every ``odom``, ``imu/data_raw``,
``uwb/range`` and ``scan`` message as published, and replays them merged in
stamp order (ties keep publication order), as a rosbag replay would.
Poses are arrays ``(N, 3)``: ``x_m, y_m, yaw_rad``.
"""

from __future__ import annotations

import heapq
from dataclasses import dataclass, field
from typing import Any, Iterator

import numpy as np

TOPICS = {"odom": "odom", "imu/data_raw": "imu", "uwb/range": "uwb", "scan": "scan"}
"""Recorded topic -> stream name."""


@dataclass
class Streams:
    """Messages of one drive, per stream, in publication order."""

    odom: list = field(default_factory=list)
    imu: list = field(default_factory=list)
    uwb: list = field(default_factory=list)
    scan: list = field(default_factory=list)

    def tap(self, topic: str, msg: Any, t_us: int) -> None:
        """Bus tap (``Bus.add_tap``): keep the messages of :data:`TOPICS`."""
        name = TOPICS.get(topic)
        if name is not None:
            getattr(self, name).append(msg)

    def counts(self) -> dict[str, int]:
        """Number of messages per stream."""
        return {name: len(getattr(self, name)) for name in TOPICS.values()}

    def merged(self, kinds: tuple[str, ...]) -> Iterator[tuple[str, Any]]:
        """``(kind, msg)`` of the streams ``kinds`` merged by header stamp."""
        def keyed(kind: str):
            for i, msg in enumerate(getattr(self, kind)):
                yield msg.header.stamp.to_us(), i, kind, msg
        for _t, _i, kind, msg in heapq.merge(*(keyed(k) for k in kinds), key=lambda e: (e[0], e[1])):
            yield kind, msg


def odom_poses(msgs: list) -> tuple[np.ndarray, np.ndarray]:
    """Stamps (N,) s and poses (N, 3) of ``nav_msgs/Odometry`` messages."""
    t_s = np.array([m.header.stamp.to_sec() for m in msgs], dtype=float)
    pose = np.array([(m.pose.pose.position.x, m.pose.pose.position.y, m.pose.pose.orientation.yaw_rad())
                     for m in msgs], dtype=float).reshape(-1, 3)
    return t_s, pose


def wrap_rad(a: np.ndarray | float) -> np.ndarray | float:
    """Angle(s) wrapped to [-pi, pi)."""
    return (np.asarray(a) + np.pi) % (2 * np.pi) - np.pi


def se2_compose(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``a (+) b``: pose(s) ``b`` given in frame ``a``, expressed in ``a``'s parent. Shapes (3,) or (N, 3)."""
    a, b = np.asarray(a, float), np.asarray(b, float)
    c, s = np.cos(a[..., 2]), np.sin(a[..., 2])
    x = a[..., 0] + c * b[..., 0] - s * b[..., 1]
    y = a[..., 1] + s * b[..., 0] + c * b[..., 1]
    return np.stack([x, y, wrap_rad(a[..., 2] + b[..., 2])], axis=-1)


def se2_between(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``a^-1 (+) b``: pose ``b`` in frame ``a``. Shapes (3,) or (N, 3)."""
    a, b = np.asarray(a, float), np.asarray(b, float)
    c, s = np.cos(a[..., 2]), np.sin(a[..., 2])
    dx, dy = b[..., 0] - a[..., 0], b[..., 1] - a[..., 1]
    return np.stack([c * dx + s * dy, -s * dx + c * dy, wrap_rad(b[..., 2] - a[..., 2])], axis=-1)


def interpolate_pose(t_s: np.ndarray, pose: np.ndarray, t_query_s: float) -> np.ndarray:
    """Pose (3,) at ``t_query_s``, linear in x, y and in the unwrapped yaw; clamped at the ends."""
    yaw = np.unwrap(pose[:, 2])
    return np.array([np.interp(t_query_s, t_s, pose[:, 0]), np.interp(t_query_s, t_s, pose[:, 1]),
                     float(wrap_rad(np.interp(t_query_s, t_s, yaw)))])


def relative_motion(t_s: np.ndarray, pose: np.ndarray, t0_s: float, t1_s: float) -> tuple[float, float, float]:
    """Motion of the body between ``t0_s`` and ``t1_s`` in its own frame at ``t0_s``: dx_m, dy_m, dyaw_rad."""
    if len(t_s) == 0:
        return 0.0, 0.0, 0.0
    d = se2_between(interpolate_pose(t_s, pose, t0_s), interpolate_pose(t_s, pose, t1_s))
    return float(d[0]), float(d[1]), float(d[2])
