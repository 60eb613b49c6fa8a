"""The plan as the local controllers see it: pruned behind the robot, cut at a horizon (nav2's
PathHandler).

The robot's progress along the plan is the index of its nearest plan point, searched only ahead
of the last one (at most ``search_m`` further): where a path passes close to itself the
projection does not jump to the later leg. :meth:`PathHandler.ahead` gives the plan points from
there out to ``horizon_m`` of path length.
"""

from __future__ import annotations

import numpy as np


class PathHandler:
    """Progress along a plan ``poses`` (N, 3): x_m, y_m, yaw_rad in ``map``."""

    def __init__(self, poses: np.ndarray, search_m: float = 2.0):
        self.poses = np.asarray(poses, float)
        seg = np.hypot(*np.diff(self.poses[:, :2], axis=0).T)
        self.s_m = np.concatenate([[0.0], np.cumsum(seg)])
        """Arc length at each point (N,), m."""
        self.length_m = float(self.s_m[-1])
        self.index = 0
        self.search_m = float(search_m)

    def update(self, x_m: float, y_m: float) -> int:
        """Move the progress to the nearest point within ``search_m`` ahead of it; return its
        index."""
        hi = int(np.searchsorted(self.s_m, self.s_m[self.index] + self.search_m, side="right"))
        window = self.poses[self.index : hi, :2]
        d = np.hypot(window[:, 0] - x_m, window[:, 1] - y_m)
        self.index += int(np.argmin(d))
        return self.index

    def distance_to_path_m(self, x_m: float, y_m: float) -> float:
        """Distance from a point to the nearest plan point from the progress on, m."""
        p = self.poses[self.index :, :2]
        return float(np.hypot(p[:, 0] - x_m, p[:, 1] - y_m).min())

    def ahead(self, horizon_m: float) -> np.ndarray:
        """Plan points (M, 3) from the progress out to ``horizon_m`` of arc length (at least
        one)."""
        hi = int(np.searchsorted(self.s_m, self.s_m[self.index] + horizon_m, side="right"))
        return self.poses[self.index : max(hi, self.index + 1)]

    @property
    def remaining_m(self) -> float:
        """Path length from the progress to the goal, m."""
        return self.length_m - float(self.s_m[self.index])

    @property
    def goal(self) -> np.ndarray:
        """The last pose (3,)."""
        return self.poses[-1]
