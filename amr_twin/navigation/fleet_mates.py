"""The robots of one fleet known to each other: their pose estimates shared over the fleet, so a
robot's people tracker leaves their returns alone (they stay obstacles in its costmap and its
collision monitor, but are not people to give way to).

Reasons and measurements: docs/explanation/navigation.md#amr_twinnavigationfleet_mates."""

from __future__ import annotations

import numpy as np


class FleetMates:
    """Every fleet member's pose source (:class:`~amr_twin.navigation.localisation.PoseSource`), as
    a fleet system shares them; a return within ``radius_m`` of another member's estimated
    centre is that member's (``radius_m``: the footprint's circumscribed radius plus the
    localisation's error, m)."""

    def __init__(self, radius_m: float):
        self.radius_m = float(radius_m)
        self._sources: list = []

    def join(self, pose_source) -> int:
        """Add a member by its pose source; returns its index."""
        self._sources.append(pose_source)
        return len(self._sources) - 1

    def others_xy_m(self, index: int) -> np.ndarray:
        """Estimated centres (M, 2) in ``map`` of the members other than ``index`` that have a
        pose."""
        xy = [s.pose()[:2] for i, s in enumerate(self._sources) if i != index and s.ready]
        return np.asarray(xy, float).reshape(-1, 2)

    def theirs(self, index: int, points_xy_m: np.ndarray) -> np.ndarray:
        """Which of ``points_xy_m`` (P, 2) in ``map`` lie within ``radius_m`` of another member
        (P,) bool."""
        mates = self.others_xy_m(index)
        p = np.asarray(points_xy_m, float).reshape(-1, 2)
        if len(mates) == 0 or len(p) == 0:
            return np.zeros(len(p), bool)
        d2 = ((p[:, None, :] - mates[None, :, :]) ** 2).sum(-1)
        return (d2 <= self.radius_m * self.radius_m).any(1)
