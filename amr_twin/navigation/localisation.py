"""Where the navigator thinks the robot is: the localisation the user picks, read from the bus.

:class:`PoseSource` subscribes to a ``nav_msgs/Odometry`` topic of the fusion stack or the
ground truth (a source of :data:`~amr_twin.navigation.registries.LOCALISATIONS`), composes it
with a fixed ``map -> frame`` transform when the topic's frame is not ``map`` (the wheel
odometry's ``odom`` starts at the start pose), and keeps
a short history so that each beam of a scan can be placed at the pose of its own instant
(:meth:`PoseSource.scan_in_map`; a rotation of the RPLIDAR takes 0.18 s, in which the robot moves
up to 0.15 m).
"""

from __future__ import annotations

import math
from collections import deque

import numpy as np

from amr_twin.analysis import se2
from amr_twin.navigation.kinematics import wrap

HISTORY_S = 1.0


class PoseSource:
    """Latest pose and twist from an odometry topic, and the poses of the last ``HISTORY_S``."""

    def __init__(self, bus, topic: str, map_from_frame=(0.0, 0.0, 0.0)):
        self.topic = topic
        self.map_from_frame = tuple(float(v) for v in map_from_frame)
        self._hist: deque = deque()
        self.velocity = (0.0, 0.0)
        """Forward speed and yaw rate of the last message (m/s, rad/s)."""
        self.correction = (0.0, 0.0, 0.0)
        """``map`` from the topic's map: ``(tx_m, ty_m, theta_rad)``, the scan matcher's
        (:mod:`.map_matching`)."""
        bus.subscribe(topic, self._on_odometry)

    def _on_odometry(self, msg) -> None:
        p = msg.pose.pose
        ox, oy, oyaw = self.map_from_frame
        c, s = math.cos(oyaw), math.sin(oyaw)
        x, y = ox + c * p.position.x - s * p.position.y, oy + s * p.position.x + c * p.position.y
        yaw = oyaw + p.orientation.yaw_rad()
        t = msg.header.stamp.to_sec()
        hist = self._hist
        if hist and t <= hist[-1][0]:
            hist.pop()
        hist.append((t, x, y, yaw))
        while hist and hist[0][0] < t - HISTORY_S:
            hist.popleft()
        self.velocity = (float(msg.twist.twist.linear.x), float(msg.twist.twist.angular.z))

    @property
    def ready(self) -> bool:
        return bool(self._hist)

    def pose(self) -> np.ndarray:
        """The latest pose (3,): x_m, y_m, yaw_rad in ``map``."""
        return self._corrected(np.array(self._hist[-1][1:]))

    def poses_at(self, t_s: np.ndarray) -> np.ndarray:
        """Poses (K, 3) at times ``t_s`` (K,), interpolated in the history (held at its ends)."""
        h = np.array(self._hist)
        yaw = np.unwrap(h[:, 3])
        out = np.column_stack(
            [
                np.interp(t_s, h[:, 0], h[:, 1]),
                np.interp(t_s, h[:, 0], h[:, 2]),
                np.interp(t_s, h[:, 0], yaw),
            ]
        )
        out[:, 2] = wrap(out[:, 2])
        return self._corrected(out)

    @property
    def stamp_s(self) -> float:
        """The latest message's stamp, s."""
        return self._hist[-1][0]

    def raw_pose(self) -> np.ndarray:
        """The latest pose (3,) of the topic in ``map``, without :attr:`correction`."""
        return np.array(self._hist[-1][1:])

    def rebase(self, before) -> None:
        """The topic's latest pose jumped from ``before`` (3,): the EKF took in the map match
        (:mod:`.map_matching`). The jump ``delta = new o before^-1`` moves the earlier history with
        it and comes out of :attr:`correction`, so that every corrected pose stays where it was."""
        new = self.raw_pose()
        delta = se2.compose(new, se2.inverse(before))
        if not np.any(delta):
            return
        hist = self._hist
        last = hist.pop()
        if hist:
            h = np.array(hist)
            moved = se2.compose(delta, h[:, 1:])
            hist.clear()
            hist.extend(
                (float(t), float(x), float(y), float(yaw)) for t, (x, y, yaw) in zip(h[:, 0], moved)
            )
        hist.append(last)
        self.correction = tuple(float(v) for v in se2.compose(self.correction, se2.inverse(delta)))

    def _corrected(self, poses: np.ndarray) -> np.ndarray:
        """Poses (K, 3) or a pose (3,) moved by :attr:`correction`."""
        return se2.compose(self.correction, poses) if any(self.correction) else poses

    def scan_in_map(self, scan, laser_xy_yaw, raytrace_range_m: float):
        """Each beam of a ``LaserScan`` in ``map``: origins (K, 2), ends (K, 2) and returns (K,)
        bool.

        A beam without a return ends ``raytrace_range_m`` out; the laser frame sits at
        ``laser_xy_yaw`` in ``base_link``.
        """
        r = np.asarray(scan.ranges, float)
        n = len(r)
        t = scan.header.stamp.to_sec() + scan.time_increment * np.arange(n)
        base = self.poses_at(t)
        lx, ly, lyaw = laser_xy_yaw
        c, s = np.cos(base[:, 2]), np.sin(base[:, 2])
        origin = np.column_stack([base[:, 0] + c * lx - s * ly, base[:, 1] + s * lx + c * ly])
        with np.errstate(invalid="ignore"):
            hit = np.isfinite(r) & (r >= scan.range_min) & (r < scan.range_max)
        rr = np.where(hit, r, raytrace_range_m)
        theta = base[:, 2] + lyaw + scan.angle_min + scan.angle_increment * np.arange(n)
        end = origin + rr[:, None] * np.column_stack([np.cos(theta), np.sin(theta)])
        return origin, end, hit
