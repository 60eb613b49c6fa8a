"""Recorded sensor streams of a drive, replayed in stamp order for the estimators.

A :class:`Streams` is a bus tap: it keeps every ``odom``, ``imu/data_raw``,
``uwb/range`` and ``scan`` message as published, and replays them merged in
stamp order (ties keep publication order), as a rosbag replay would.
Poses are arrays ``(N, 3)``: ``x_m, y_m, yaw_rad`` (algebra in :mod:`amr_twin.analysis.se2`).
"""

from __future__ import annotations

import heapq
from dataclasses import dataclass, field
from typing import Any, Iterator

import numpy as np

from amr_twin.analysis import se2

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

        for _t, _i, kind, msg in heapq.merge(
            *(keyed(k) for k in kinds), key=lambda e: (e[0], e[1])
        ):
            yield kind, msg


def odom_poses(msgs: list) -> tuple[np.ndarray, np.ndarray]:
    """Stamps (N,) s and poses (N, 3) of ``nav_msgs/Odometry`` messages."""
    t_s = np.array([m.header.stamp.to_sec() for m in msgs], dtype=float)
    pose = np.array(
        [
            (m.pose.pose.position.x, m.pose.pose.position.y, m.pose.pose.orientation.yaw_rad())
            for m in msgs
        ],
        dtype=float,
    ).reshape(-1, 3)
    return t_s, pose


def relative_motion(
    t_s: np.ndarray, pose: np.ndarray, t0_s: float, t1_s: float
) -> tuple[float, float, float]:
    """Motion of the body between ``t0_s`` and ``t1_s`` in its own frame at ``t0_s``: dx_m, dy_m,
    dyaw_rad."""
    if len(t_s) == 0:
        return 0.0, 0.0, 0.0
    d = se2.between(se2.interpolate(t_s, pose, t0_s), se2.interpolate(t_s, pose, t1_s))
    return float(d[0]), float(d[1]), float(d[2])
