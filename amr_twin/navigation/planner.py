"""The global planner: Dijkstra on the costmap's 8-connected grid, line-of-sight shortening, a dense
path.

Reasons and measurements: docs/explanation/navigation.md#amr_twinnavigationplanner."""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np

from amr_twin.navigation.costmap import INSCRIBED, Costmap, goal_problem, inflation_cost
from amr_twin.navigation.footprint import Footprint
from amr_twin.navigation.grid_graph import GridGraph
from amr_twin.navigation.passages import split


@dataclass(frozen=True)
class Plan:
    """A planned path: points (N, 3) ``x_m, y_m, yaw_rad`` in ``map``, its length and planning CPU
    time."""

    poses: np.ndarray
    length_m: float
    cpu_s: float

    @property
    def xy_m(self) -> np.ndarray:
        return self.poses[:, :2]


class GlobalPlanner:
    """A* on a :class:`Costmap` with shortening (module docstring)."""

    def __init__(
        self,
        costmap: Costmap,
        downsample: int = 2,
        cost_weight: float = 1.0,
        clearance_m: float = 0.6,
        spacing_m: float = 0.05,
        turn_room_m: float = 0.0,
        unmapped_pad_m: float = 0.0,
        people_m: float = 0.0,
        footprint: Footprint | None = None,
        footprint_clearance_m: float = 0.1,
        lead_m: float = 0.35,
    ):
        self.costmap, self.downsample = costmap, int(downsample)
        self.footprint, self.footprint_clearance_m, self.lead_m = (
            footprint,
            float(footprint_clearance_m),
            float(lead_m),
        )
        self.unmapped_pad_m, self.people_m = float(unmapped_pad_m), float(people_m)
        self._coarse, self._seen, self._graph = None, -1, None
        self.turn_room_m = float(turn_room_m)
        self.cost_weight, self.clearance_m, self.spacing_m = (
            float(cost_weight),
            float(clearance_m),
            float(spacing_m),
        )
        self.last_error = ""

    def _pooled(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The coarse grids (worst cost, least distance, least distance to the obstacle layer),
        brought up to date over the windows the costmap changed since the last plan (all of them the
        first time)."""
        k, cm = self.downsample, self.costmap
        rows, cols = cm.shape[0] // k * k, cm.shape[1] // k * k
        seen = self._seen
        if (
            self._coarse is None
            or (cm.changes and seen < cm.changes[0][0] - 1)
            or any(w is None for v, w in cm.changes if v > seen)
        ):
            windows = [(0, rows, 0, cols)]
            self._coarse = [
                np.zeros((rows // k, cols // k), t) for t in (np.uint8, np.float32, np.float32)
            ]
        else:
            windows = [w for v, w in cm.changes if v > seen]
        for r0, r1, c0, c1 in windows:
            r0, c0 = r0 // k * k, c0 // k * k
            r1, c1 = min(-(-r1 // k) * k, rows), min(-(-c1 // k) * k, cols)
            if r1 <= r0 or c1 <= c0:
                continue
            dist = cm.dist_m[r0:r1, c0:c1]
            for i, (a, how) in enumerate(
                (
                    (
                        inflation_cost(
                            dist, cm.inscribed_m, cm.inflation_radius_m, cm.cost_scaling_per_m
                        ),
                        np.max,
                    ),
                    (dist, np.min),
                    (cm.obstacle_dist_m[r0:r1, c0:c1], np.min),
                )
            ):
                pooled = how(a.reshape((r1 - r0) // k, k, (c1 - c0) // k, k), axis=(1, 3))
                self._coarse[i][r0 // k : r1 // k, c0 // k : c1 // k] = pooled
        self._seen = cm.version
        return self._coarse

    def _weights(self, keep_m: float, people_xy_m=None, pad_m: float = 0.0) -> np.ndarray:
        """Coarse cell weights; cells closer than ``keep_m`` to an obstacle, or than ``people_m`` to
        a person at ``people_xy_m`` (N, 2), blocked (inf)."""
        cm = self.costmap
        coarse, near, near_obstacle = self._pooled()
        w = 1.0 + self.cost_weight * coarse / 252.0
        blocked = (coarse >= INSCRIBED) | (near < keep_m)
        if cm.marked.any():  # what the map does not hold (people, pallet jacks): kept farther from
            blocked |= near_obstacle < max(keep_m, cm.inscribed_m) + pad_m
        size = cm.resolution_m * self.downsample
        for x, y in np.zeros((0, 2)) if people_xy_m is None else people_xy_m:
            c0, r0 = (
                int((x - self.people_m - cm.origin_xy_m[0]) // size),
                int((y - self.people_m - cm.origin_xy_m[1]) // size),
            )
            n = int(2 * self.people_m // size) + 2
            rr, cc = np.mgrid[
                max(r0, 0) : min(r0 + n, w.shape[0]), max(c0, 0) : min(c0 + n, w.shape[1])
            ]
            inside = (
                np.hypot(
                    cm.origin_xy_m[0] + (cc + 0.5) * size - x,
                    cm.origin_xy_m[1] + (rr + 0.5) * size - y,
                )
                < self.people_m
            )
            blocked[rr[inside], cc[inside]] = True
        w[blocked] = np.inf
        return w

    def plan(
        self, start_xy_m, goal_xy_m, goal_yaw_rad: float | None = None, people_xy_m=None
    ) -> Plan | None:
        """A plan from ``start_xy_m`` to ``goal_xy_m`` (the last heading ``goal_yaw_rad`` if given)
        keeping the robot's centre ``people_m`` from the people standing at ``people_xy_m`` (N, 2),
        or None (:attr:`last_error` says why)."""
        t0 = time.process_time()
        problem = goal_problem(self.costmap, goal_xy_m)
        if problem:
            self.last_error = problem
            return None
        cm, k = self.costmap, self.downsample
        for keep_m, pad_m in (
            (self.turn_room_m, self.unmapped_pad_m),
            (0.0, self.unmapped_pad_m),
            (0.0, 0.0),
        ):
            path = self._search(start_xy_m, goal_xy_m, keep_m, people_xy_m, pad_m)
            if path is not None and not isinstance(path, str):
                break
        if isinstance(path, str):
            self.last_error = path
            return None
        if path is None:
            self.last_error = (
                f"no path from ({start_xy_m[0]:.2f}, {start_xy_m[1]:.2f}) to "
                f"({goal_xy_m[0]:.2f}, {goal_xy_m[1]:.2f}): the goal is cut off"
            )
            return None
        xy = cm.origin_xy_m + (path[:, ::-1] + 0.5) * cm.resolution_m * k
        xy[0], xy[-1] = start_xy_m[:2], goal_xy_m[:2]
        people = (
            np.zeros((0, 2))
            if people_xy_m is None
            else np.asarray(people_xy_m, float).reshape(-1, 2)
        )
        if self.footprint is None:
            xy = self._shorten(xy, people)
        else:
            parts = [
                piece if fixed else self._shorten(piece, people)
                for fixed, piece in split(
                    cm, self.footprint, xy, self.footprint_clearance_m, self.lead_m
                )
            ]
            xy = np.vstack([parts[0]] + [p[1:] for p in parts[1:]])
        poses = self._resample(xy, goal_yaw_rad)
        length = float(np.hypot(*np.diff(poses[:, :2], axis=0).T).sum())
        return Plan(poses, length, time.process_time() - t0)

    def path_free(self, xy_m: np.ndarray, people_xy_m=None) -> bool:
        """Whether a path's points ``xy_m`` (N, 2) still pass where the planner's second tier would
        (the inscribed radius from obstacles, ``unmapped_pad_m`` more from the obstacle layer's,
        ``people_m`` from people standing at ``people_xy_m``), the last point (the goal's cell)
        aside."""
        cm, k = self.costmap, self.downsample
        w = self._weights(0.0, people_xy_m, self.unmapped_pad_m)
        r, c, inside = cm.cells(np.asarray(xy_m, float)[:-1])
        return bool(inside.all()) and bool(
            np.isfinite(
                w[np.minimum(r // k, w.shape[0] - 1), np.minimum(c // k, w.shape[1] - 1)]
            ).all()
        )

    def _search(self, start_xy_m, goal_xy_m, keep_m: float, people_xy_m=None, pad_m: float = 0.0):
        """Coarse cells of the cheapest path keeping ``keep_m`` from obstacles, ``pad_m`` more from
        those of the obstacle layer (None: none; a str: why not)."""
        cm, k = self.costmap, self.downsample
        w = self._weights(keep_m, people_xy_m, pad_m)
        cell = []
        for name, xy in (("the start", start_xy_m), ("the goal", goal_xy_m)):
            r, c, inside = cm.cells(np.asarray(xy, float)[None])
            if not inside[0]:
                return f"{name} ({xy[0]:.2f}, {xy[1]:.2f}) lies outside the map"
            cell.append((min(int(r[0]) // k, w.shape[0] - 1), min(int(c[0]) // k, w.shape[1] - 1)))
        w[cell[0]] = (
            min(w[cell[0]], 1.0 + self.cost_weight)
            if np.isfinite(w[cell[0]])
            else 1.0 + self.cost_weight
        )
        if not np.isfinite(w[cell[1]]):
            w[cell[1]] = 1.0 + self.cost_weight  # a goal cell shared with an obstacle's coarse cell
        if self._graph is None or self._graph.shape != w.shape:
            self._graph = GridGraph(w.shape)
        return self._graph.shortest(w, cell[0], cell[1])

    def _clearance(
        self, a: np.ndarray, b: np.ndarray, people_xy_m: np.ndarray
    ) -> tuple[float, float]:
        """Least clearance along the segment a-b to an obstacle, and to a person less ``people_m``
        (may be < 0)."""
        n = max(2, int(math.ceil(np.hypot(*(b - a)) / (0.5 * self.costmap.resolution_m))) + 1)
        pts = a + np.linspace(0.0, 1.0, n)[:, None] * (b - a)
        return float(self.costmap.distance_at(pts).min()), float(
            self._people_clearance(pts, people_xy_m).min()
        )

    def _people_clearance(self, xy: np.ndarray, people_xy_m: np.ndarray) -> np.ndarray:
        """Distance (K,) of points to the nearest person less ``people_m`` (inf without people),
        m."""
        if len(people_xy_m) == 0:
            return np.full(len(xy), np.inf)
        return (
            np.hypot(xy[:, None, 0] - people_xy_m[:, 0], xy[:, None, 1] - people_xy_m[:, 1]).min(1)
            - self.people_m
        )

    def _shorten(self, xy: np.ndarray, people_xy_m: np.ndarray) -> np.ndarray:
        """Line-of-sight shortening (module docstring, step 3), keeping as far from people as the
        grid path did."""
        d, dp = self.costmap.distance_at(xy), self._people_clearance(xy, people_xy_m)
        floor, half = self.costmap.inscribed_m, 0.5 * self.costmap.resolution_m
        keep, i, n = [0], 0, len(xy)

        def clear(j: int) -> bool:
            need = max(min(float(d[i : j + 1].min()), self.clearance_m) - half, floor)
            obstacle, person = self._clearance(xy[i], xy[j], people_xy_m)
            return obstacle >= need and person >= min(float(dp[i : j + 1].min()), 0.0) - half

        while i < n - 1:
            good, step = i + 1, 1
            while good + step < n and clear(good + step):  # gallop, then bisect
                good += step
                step *= 2
            lo, hi = good, min(good + step, n - 1)
            while hi - lo > 1:
                mid = (lo + hi) // 2
                lo, hi = (mid, hi) if clear(mid) else (lo, mid)
            if hi != lo and clear(hi):
                lo = hi
            keep.append(lo)
            i = lo
        return xy[keep]

    def _resample(self, xy: np.ndarray, goal_yaw_rad: float | None) -> np.ndarray:
        xy = xy[np.concatenate([[True], np.hypot(*np.diff(xy, axis=0).T) > 1e-9])]
        seg = np.diff(xy, axis=0)
        seg_len = np.hypot(seg[:, 0], seg[:, 1])
        if len(seg_len) == 0 or seg_len.sum() < 1e-9:
            yaw = 0.0 if goal_yaw_rad is None else goal_yaw_rad
            return np.array([[xy[-1, 0], xy[-1, 1], yaw]])
        s = np.concatenate([[0.0], np.cumsum(seg_len)])
        t = np.append(np.arange(0.0, s[-1], self.spacing_m), s[-1])
        x, y = np.interp(t, s, xy[:, 0]), np.interp(t, s, xy[:, 1])
        idx = np.clip(np.searchsorted(s, t, side="right") - 1, 0, len(seg) - 1)
        yaw = np.arctan2(seg[idx, 1], seg[idx, 0])
        if goal_yaw_rad is not None:
            yaw[-1] = goal_yaw_rad
        return np.column_stack([x, y, yaw])
