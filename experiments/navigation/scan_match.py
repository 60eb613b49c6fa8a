"""Scan-to-map matching of the mapping drive: each scan fitted to the map of the scans before it.

Reasons and measurements: docs/explanation/navigation.md#amr_twinexperimentsnavigationscan_match."""

from __future__ import annotations

import math

import numpy as np
from scipy.ndimage import distance_transform_edt, map_coordinates


def _end_points(scan, poses: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Map-frame end points (K, 2) of a scan's returns and their beams' indices (K,)."""
    r = np.asarray(scan.ranges, float)
    with np.errstate(invalid="ignore"):
        hit = np.flatnonzero(np.isfinite(r) & (r >= scan.range_min) & (r < scan.range_max))
    theta = poses[hit, 2] + scan.angle_min + scan.angle_increment * hit
    return np.column_stack(
        [poses[hit, 0] + r[hit] * np.cos(theta), poses[hit, 1] + r[hit] * np.sin(theta)]
    ), hit


def _apply(delta, centre: np.ndarray, xy: np.ndarray) -> np.ndarray:
    c, s = math.cos(delta[2]), math.sin(delta[2])
    d = xy - centre
    return np.column_stack(
        [
            centre[0] + c * d[:, 0] - s * d[:, 1] + delta[0],
            centre[1] + s * d[:, 0] + c * d[:, 1] + delta[1],
        ]
    )


class _HitMap:
    """Cells hit by the scans so far, on a grid of ``resolution_m`` from ``origin_xy_m`` (row 0 at
    the lowest y)."""

    def __init__(self, origin_xy_m, shape: tuple[int, int], resolution_m: float):
        self.origin, self.res = np.asarray(origin_xy_m, float), float(resolution_m)
        self.hits = np.zeros(shape, bool)

    def add(self, xy: np.ndarray) -> None:
        rc = np.floor((xy[:, ::-1] - self.origin[::-1]) / self.res).astype(int)
        ok = (rc >= 0).all(1) & (rc[:, 0] < self.hits.shape[0]) & (rc[:, 1] < self.hits.shape[1])
        self.hits[rc[ok, 0], rc[ok, 1]] = True

    def field(self, centre_xy: np.ndarray, half_m: float):
        """Distance to the nearest hit (m) on a window about ``centre_xy``, its gradient, and the
        window's corner cell."""
        n = int(half_m / self.res)
        r0, c0 = np.floor((centre_xy[::-1] - self.origin[::-1]) / self.res).astype(int) - n
        r0, c0 = max(r0, 0), max(c0, 0)
        win = self.hits[r0 : r0 + 2 * n, c0 : c0 + 2 * n]
        if not win.any():
            return None
        d = distance_transform_edt(~win) * self.res
        return d, np.gradient(d, self.res), (r0, c0)


def match_scans(
    scans: list,
    beam_poses: list,
    origin_xy_m,
    shape: tuple[int, int],
    resolution_m: float,
    *,
    warmup: int = 20,
    window_m: float = 7.0,
    inlier_m: float = 0.3,
    prior_m: float = 0.05,
    prior_rad: float = 0.01,
    ekf_m: float = 0.1,
    ekf_rad: float = 0.02,
    iterations: int = 6,
) -> tuple[list, np.ndarray]:
    """Beam poses (each (n_beams, 3)) corrected by scan-to-map matching (module docstring), and the
    corrections (n_scans, 3): dx_m, dy_m, dyaw_rad."""
    hit_map = _HitMap(origin_xy_m, shape, resolution_m)
    delta = np.zeros(3)
    out, corrections = [], np.zeros((len(scans), 3))
    prior = np.diag([1.0 / prior_m**2, 1.0 / prior_m**2, 1.0 / prior_rad**2])
    anchor = np.diag([1.0 / ekf_m**2, 1.0 / ekf_m**2, 1.0 / ekf_rad**2])
    for k, (scan, poses) in enumerate(zip(scans, beam_poses)):
        poses = np.asarray(poses, float)
        xy, _beams = _end_points(scan, poses)
        centre = poses[len(poses) // 2, :2]
        f = hit_map.field(centre, window_m) if k >= warmup and len(xy) >= 20 else None
        if f is not None:
            d, (gy, gx), (r0, c0) = f
            last = delta.copy()
            for _ in range(iterations):
                p = _apply(delta, centre, xy)
                rc = np.vstack(
                    [
                        (p[:, 1] - hit_map.origin[1]) / resolution_m - 0.5 - r0,
                        (p[:, 0] - hit_map.origin[0]) / resolution_m - 0.5 - c0,
                    ]
                )
                dist = map_coordinates(d, rc, order=1, mode="nearest")
                inside = (
                    (rc >= 0).all(0)
                    & (rc[0] < d.shape[0] - 1)
                    & (rc[1] < d.shape[1] - 1)
                    & (dist < inlier_m)
                )
                if inside.sum() < 20:
                    break
                g = np.column_stack(
                    [
                        map_coordinates(gx, rc[:, inside], order=1),
                        map_coordinates(gy, rc[:, inside], order=1),
                    ]
                )
                q = p[inside] - centre - delta[:2]
                J = np.column_stack([g[:, 0], g[:, 1], -g[:, 0] * q[:, 1] + g[:, 1] * q[:, 0]])
                H = J.T @ J / inlier_m**2 + prior + anchor
                b = J.T @ dist[inside] / inlier_m**2 + prior @ (delta - last) + anchor @ delta
                step = np.linalg.solve(H, -b)
                delta = delta + step
                if abs(step[0]) + abs(step[1]) < 1e-4 and abs(step[2]) < 1e-5:
                    break
        corrections[k] = delta
        moved = poses.copy()
        moved[:, :2] = _apply(delta, centre, poses[:, :2])
        moved[:, 2] += delta[2]
        out.append(moved)
        hit_map.add(_apply(delta, centre, xy))
    return out, corrections
