"""A layered costmap as nav2's: static layer, obstacle layer with marking and ray-traced clearing,
inflation.

Reasons and measurements: docs/explanation/navigation.md#amr_twinnavigationcostmap."""

from __future__ import annotations

import ctypes
import math
from pathlib import Path

import numpy as np
from scipy.ndimage import distance_transform_edt

from amr_twin.navigation.static_map import StaticMap
from amr_twin.base.native_build import address, c_array, open_helper

C_SOURCE = Path(__file__).with_name("costmap_rays.c")

LETHAL, INSCRIBED, NO_INFORMATION = 254, 253, 255
KEEP_CHANGES = 256


def inflation_cost(
    dist_m: np.ndarray, inscribed_m: float, inflation_radius_m: float, cost_scaling_per_m: float
) -> np.ndarray:
    """nav2's inflation cost (uint8) of cells at ``dist_m`` from the nearest lethal cell."""
    d = np.asarray(dist_m, np.float32)
    cost = np.where(
        d <= inflation_radius_m, 252.0 * np.exp(-cost_scaling_per_m * (d - inscribed_m)), 0.0
    )
    cost = np.where(d <= inscribed_m, INSCRIBED, np.minimum(cost, 252.0))
    return np.where(d <= 0.0, LETHAL, cost).astype(np.uint8)


class Costmap:
    """Static, obstacle and inflation layers on the grid of ``static``.

    Parameters
    ----------
    static : StaticMap
    inscribed_radius_m : float
        The footprint's inscribed radius (:class:`~amr_twin.navigation.footprint.Footprint`), m.
    inflation_radius_m, cost_scaling_per_m : float
        nav2's ``inflation_radius`` (m) and ``cost_scaling_factor`` (1/m).
    unknown_is_lethal : bool
        Unknown cells of the map are obstacles.
    static_tolerance_m : float
        Returns this close to a static obstacle are not marked, m.
    native : bool
        False: the clearing march by NumPy rather than its C twin (``costmap_rays.c``;
        :attr:`engine` says which).
    """

    def __init__(
        self,
        static: StaticMap,
        inscribed_radius_m: float,
        inflation_radius_m: float,
        cost_scaling_per_m: float,
        unknown_is_lethal: bool = True,
        static_tolerance_m: float = 0.15,
        native: bool = True,
    ):
        self.static = static
        self.resolution_m = static.resolution_m
        self.origin_xy_m = np.asarray(static.origin_xy_m, float)
        self.shape = static.shape
        self.inscribed_m = float(inscribed_radius_m)
        self.inflation_radius_m = float(inflation_radius_m)
        self.cost_scaling_per_m = float(cost_scaling_per_m)
        self.static_lethal = static.occupied | (static.unknown if unknown_is_lethal else False)
        self._pad = int(math.ceil(self.inflation_radius_m / self.resolution_m)) + 1
        self.static_dist_m = self._distance(self.static_lethal)
        near = self.static_dist_m <= static_tolerance_m + 1e-6
        self._near_static = near
        self.marked = np.zeros(self.shape, bool)
        """The obstacle layer: cells marked by the scan."""
        self._marked_u8 = self.marked.view(np.uint8)  # the same memory, for the C helper
        self._lib, self.engine = open_helper(C_SOURCE, native)
        if self._lib is not None:
            ptr = ctypes.c_void_p
            self._lib.costmap_crossed.argtypes = [
                ctypes.c_int,
                ptr,
                ptr,
                ptr,
                ctypes.c_double,
                ctypes.c_double,
                ctypes.c_double,
                ctypes.c_double,
                ctypes.c_int,
                ctypes.c_int,
                ptr,
                ptr,
            ]
            self._lib.costmap_crossed.restype = ctypes.c_int64
        self.dist_m = self.static_dist_m.copy()
        """Distance from each cell to the nearest lethal cell of either layer, capped, m
        (float32)."""
        self._cap = np.float32(self.inflation_radius_m + self.resolution_m)
        self.obstacle_dist_m = np.full(self.shape, self._cap, np.float32)
        """Distance from each cell to the nearest cell of the obstacle layer alone, capped, m
        (float32)."""
        self.updates = 0
        self.version = 0
        """Counts the changes of the layers; :attr:`changes` keeps the last ones' windows."""
        self.changes: list[tuple[int, tuple[int, int, int, int] | None]] = []
        """``(version, (r0, r1, c0, c1))`` of each change, rows r0..r1-1 and columns c0..c1-1 (None:
        all)."""

    def _distance(self, lethal: np.ndarray) -> np.ndarray:
        if not lethal.any():
            return np.full(lethal.shape, self.inflation_radius_m + self.resolution_m, np.float32)
        d = distance_transform_edt(~lethal) * self.resolution_m
        return np.minimum(d, self.inflation_radius_m + self.resolution_m).astype(np.float32)

    # -- geometry -----------------------------------------------------------------------
    def cells(self, xy_m: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Row, column and on-the-grid flag of map-frame points (K, 2)."""
        xy = np.asarray(xy_m, float).reshape(-1, 2)
        col = np.floor((xy[:, 0] - self.origin_xy_m[0]) / self.resolution_m).astype(np.int64)
        row = np.floor((xy[:, 1] - self.origin_xy_m[1]) / self.resolution_m).astype(np.int64)
        inside = (row >= 0) & (row < self.shape[0]) & (col >= 0) & (col < self.shape[1])
        return row, col, inside

    def centres_xy_m(self, rows: np.ndarray, cols: np.ndarray) -> np.ndarray:
        """Map-frame centres (K, 2) of cells, m."""
        return self.origin_xy_m + (np.column_stack([cols, rows]) + 0.5) * self.resolution_m

    def distance_at(self, xy_m: np.ndarray) -> np.ndarray:
        """Distance to the nearest lethal cell at map-frame points (K,), m; 0 off the grid."""
        row, col, inside = self.cells(xy_m)
        out = np.zeros(len(row), np.float32)
        out[inside] = self.dist_m[row[inside], col[inside]]
        return out

    def static_distance_at(self, xy_m: np.ndarray) -> np.ndarray:
        """Distance to the nearest lethal cell of the static layer alone at points (K,), m; 0 off
        the grid."""
        row, col, inside = self.cells(xy_m)
        out = np.zeros(len(row), np.float32)
        out[inside] = self.static_dist_m[row[inside], col[inside]]
        return out

    def obstacle_distance_at(self, xy_m: np.ndarray) -> np.ndarray:
        """Distance to the nearest cell of the obstacle layer (what the map does not hold) at points
        (K,), m."""
        row, col, inside = self.cells(xy_m)
        out = np.full(len(row), self._cap, np.float32)
        out[inside] = self.obstacle_dist_m[row[inside], col[inside]]
        return out

    def cost(self) -> np.ndarray:
        """The combined cost of every cell, (rows, cols) uint8 (nav2's values)."""
        return inflation_cost(
            self.dist_m, self.inscribed_m, self.inflation_radius_m, self.cost_scaling_per_m
        )

    # -- obstacle layer ----------------------------------------------------------------
    def update_scan(
        self,
        origins_xy_m: np.ndarray,
        ends_xy_m: np.ndarray,
        hit: np.ndarray,
        obstacle_range_m: float,
        raytrace_range_m: float,
    ) -> int:
        """Clear along the beams, then mark their returns; return how many cells changed.

        ``origins_xy_m`` (K, 2): the laser's position at each beam's instant; ``ends_xy_m`` (K, 2):
        the beam's end (its return, or any point along it without one); ``hit`` (K,): a return.
        """
        o = np.asarray(origins_xy_m, float).reshape(-1, 2)
        e = np.asarray(ends_xy_m, float).reshape(-1, 2)
        hit = np.asarray(hit, bool)
        v = e - o
        length = np.hypot(v[:, 0], v[:, 1])
        u = v / np.maximum(length, 1e-9)[:, None]
        free_len = np.where(
            hit, np.minimum(length - 0.5 * self.resolution_m, raytrace_range_m), raytrace_range_m
        )
        marked = self.marked.reshape(-1)  # a view: writes go to the layer
        cleared = np.unique(
            self._crossed(o, u, free_len)
        )  # few: the cells marked before and crossed now
        marked[cleared] = False
        near = hit & (length <= obstacle_range_m)
        row, col, inside = self.cells(e[near])
        row, col = row[inside], col[inside]
        keep = ~self._near_static[row, col]
        mark = np.unique(row[keep] * self.shape[1] + col[keep])
        was = marked[mark] | np.isin(mark, cleared, assume_unique=True)  # marked before this scan
        changed = np.union1d(np.setdiff1d(cleared, mark, assume_unique=True), mark[~was])
        marked[mark] = True
        if len(changed):
            r, c = np.divmod(changed, self.shape[1])
            self._refresh(r.min(), r.max(), c.min(), c.max())
        self.updates += 1
        return int(len(changed))

    def _crossed(self, o: np.ndarray, u: np.ndarray, free_len: np.ndarray) -> np.ndarray:
        """Flat indices of the marked cells that beams from ``o`` (K, 2) along ``u`` (K, 2) cross,
        sampled every 0.75 cell out to ``free_len`` (K,) m (with repeats); the C helper's loop or
        its NumPy twin (the same cells)."""
        step = 0.75 * self.resolution_m
        beams = np.flatnonzero(free_len > 0)
        counts = np.floor(free_len[beams] / step).astype(np.int64) + 1
        if self._lib is not None:
            out = np.empty(int(counts.sum()), np.int64)
            o, u, free_len = (c_array(a, np.float64) for a in (o, u, free_len))
            n = self._lib.costmap_crossed(
                len(o),
                address(o),
                address(u),
                address(free_len),
                step,
                *self.origin_xy_m,
                self.resolution_m,
                *self.shape,
                address(self._marked_u8),
                address(out),
            )
            return out[:n]
        ray = np.repeat(beams, counts)
        first = np.repeat(np.cumsum(counts) - counts, counts)
        dist = (np.arange(len(ray)) - first) * step
        row, col, inside = self.cells(o[ray] + dist[:, None] * u[ray])
        flat = row[inside] * self.shape[1] + col[inside]
        return flat[self.marked.reshape(-1)[flat]]

    def _refresh(self, r0: int, r1: int, c0: int, c1: int) -> None:
        """Recompute the distances of the cells within the inflation radius of rows r0..r1, cols
        c0..c1."""
        p = self._pad
        R0, R1 = max(r0 - p, 0), min(r1 + p + 1, self.shape[0])
        C0, C1 = max(c0 - p, 0), min(c1 + p + 1, self.shape[1])
        S0, S1 = (
            max(R0 - p, 0),
            min(R1 + p, self.shape[0]),
        )  # the window's own surroundings count too
        T0, T1 = max(C0 - p, 0), min(C1 + p, self.shape[1])
        marked = self.marked[S0:S1, T0:T1]
        core = np.s_[R0 - S0 : R1 - S0, C0 - T0 : C1 - T0]
        self.dist_m[R0:R1, C0:C1] = self._distance(self.static_lethal[S0:S1, T0:T1] | marked)[core]
        self.obstacle_dist_m[R0:R1, C0:C1] = self._distance(marked)[core]
        self._changed((R0, R1, C0, C1))

    def _changed(self, window) -> None:
        self.version += 1
        self.changes.append((self.version, window))
        del self.changes[:-KEEP_CHANGES]

    def clear(self) -> None:
        """Forget the obstacle layer (nav2's ClearEntireCostmap)."""
        self.marked[:] = False
        self.dist_m[:] = self.static_dist_m
        self.obstacle_dist_m[:] = self._cap
        self._changed(None)


def goal_problem(costmap: Costmap, goal_xy_m) -> str:
    """Why a goal cannot be planned to, in one line ('' when it can): off the map, or too close to
    an obstacle."""
    gx, gy = float(goal_xy_m[0]), float(goal_xy_m[1])
    r, c, inside = costmap.cells(np.array([[gx, gy]]))
    if not inside[0]:
        lo = costmap.origin_xy_m
        hi = lo + np.array(costmap.shape[::-1]) * costmap.resolution_m
        return (
            f"goal ({gx:.2f}, {gy:.2f}) lies outside the map "
            f"(x {lo[0]:.2f} to {hi[0]:.2f}, y {lo[1]:.2f} to {hi[1]:.2f} m)"
        )
    d = float(costmap.dist_m[r[0], c[0]])
    if d <= 0.0:
        return f"goal ({gx:.2f}, {gy:.2f}) lies inside an obstacle of the map"
    if d <= costmap.inscribed_m:
        return (
            f"goal ({gx:.2f}, {gy:.2f}) lies {d:.2f} m from an obstacle of the map, closer than "
            f"the "
            f"robot's half width ({costmap.inscribed_m:.3f} m)"
        )
    return ""
