"""The localisation's pose held to the map: each scan fitted to the static map (AMCL's role in
nav2).

Reasons and measurements: docs/explanation/navigation.md#amr_twinnavigationmap_matching."""

from __future__ import annotations

import math

import numpy as np

from amr_twin.analysis import se2
from amr_twin.navigation.kinematics import to_map
from amr_twin.ros.geometry_messages import (
    Point,
    Pose,
    PoseWithCovariance,
    PoseWithCovarianceStamped,
    Quaternion,
)
from amr_twin.ros.messages import Header, Time


class MapMatcher:
    """Fits each scan to the static map of ``costmap`` and keeps the correction (module
    docstring)."""

    def __init__(
        self,
        costmap,
        *,
        inlier_m: float = 0.3,
        iterations: int = 4,
        min_inliers: int = 40,
        max_range_m: float = 8.0,
        sigma_m: float = 0.05,
        step_m: float = 0.05,
        step_rad: float = 0.02,
        total_m: float = 0.5,
        total_rad: float = 0.2,
        feedback: bool = False,
        feedback_inflation: float = 1.0,
        feedback_floor_m: float = 0.05,
        feedback_floor_rad: float = 0.01,
    ):
        self.costmap = costmap
        self.inlier_m, self.iterations, self.min_inliers = (
            inlier_m,
            int(iterations),
            int(min_inliers),
        )
        self.max_range_m, self.sigma_m = max_range_m, sigma_m
        self.step_m, self.step_rad, self.total_m, self.total_rad = (
            step_m,
            step_rad,
            total_m,
            total_rad,
        )
        self.feedback, self.feedback_inflation = bool(feedback), feedback_inflation
        self.feedback_floor = (
            np.array([feedback_floor_m, feedback_floor_m, feedback_floor_rad]) ** 2
        )
        self.correction = (0.0, 0.0, 0.0)
        """``map`` from the localisation's frame: ``(tx_m, ty_m, theta_rad)``."""
        self.information = np.zeros((3, 3))
        """The last fit's information ``J' J / sigma^2`` (3, 3) in its increment ``(dx_m, dy_m,
        dyaw_rad)`` about the laser at :attr:`centre_xy_m`."""
        self.centre_xy_m = np.zeros(2)
        self.matches = 0
        self.skipped = 0

    def _field(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Distance to the static map's obstacles (K,) and its gradient (K, 2) at points ``q`` (K,
        2), m: the costmap's distance field (between cell centres) interpolated bilinearly, less
        half a cell, so that a point on an obstacle's face reads 0; ``inf`` off the grid."""
        cm = self.costmap
        D, res = cm.static_dist_m, cm.resolution_m
        u = (q[:, 0] - cm.origin_xy_m[0]) / res - 0.5
        v = (q[:, 1] - cm.origin_xy_m[1]) / res - 0.5
        j, i = np.floor(u).astype(np.int64), np.floor(v).astype(np.int64)
        inside = (i >= 0) & (i < D.shape[0] - 1) & (j >= 0) & (j < D.shape[1] - 1)
        i, j = np.where(inside, i, 0), np.where(inside, j, 0)
        fu, fv = u - j, v - i
        d00, d01, d10, d11 = (
            D[i, j].astype(float),
            D[i, j + 1].astype(float),
            D[i + 1, j].astype(float),
            D[i + 1, j + 1].astype(float),
        )
        d = (1 - fv) * ((1 - fu) * d00 + fu * d01) + fv * ((1 - fu) * d10 + fu * d11) - 0.5 * res
        g = (
            np.column_stack(
                [
                    (1 - fv) * (d01 - d00) + fv * (d11 - d10),
                    (1 - fu) * (d10 - d00) + fu * (d11 - d01),
                ]
            )
            / res
        )
        return np.where(inside, d, np.inf), g

    def update(self, laser_xy_m, points_xy_m: np.ndarray) -> tuple[float, float, float]:
        """Fit one scan: its returns ``points_xy_m`` (P, 2) in ``map`` as the corrected poses place
        them, seen from ``laser_xy_m`` (2,); returns the increment composed into :attr:`correction`
        (zero when too few returns lie near the map)."""
        c = np.asarray(laser_xy_m, float)
        p = np.asarray(points_xy_m, float).reshape(-1, 2)
        p = p[np.hypot(*(p - c).T) <= self.max_range_m] - c
        if len(p) < self.min_inliers:
            self.skipped += 1
            return (0.0, 0.0, 0.0)
        w_step = np.array([self.step_m, self.step_m, self.step_rad]) ** -2
        x = np.zeros(3)
        at_laser = (
            to_map(np.array([self.correction]), c[None])[0, 0] - c
        )  # the correction's move of the laser
        total = np.array([at_laser[0], at_laser[1], self.correction[2]])
        for _ in range(self.iterations):
            cs, sn = math.cos(x[2]), math.sin(x[2])
            q = np.column_stack([cs * p[:, 0] - sn * p[:, 1], sn * p[:, 0] + cs * p[:, 1]])
            d, g = self._field(q + c + x[:2])
            inlier = np.abs(d) <= self.inlier_m
            if inlier.sum() < self.min_inliers:
                self.skipped += 1
                return (0.0, 0.0, 0.0)
            J = np.column_stack(
                [g[inlier], g[inlier, 1] * q[inlier, 0] - g[inlier, 0] * q[inlier, 1]]
            )
            info = J.T @ J / self.sigma_m**2
            A = info + np.diag(w_step)
            b = -J.T @ d[inlier] / self.sigma_m**2 - w_step * x
            x = x + np.linalg.solve(A, b)
        # bounds: the step of a scan, then the whole correction (a match slid along look-alike racks
        # stops there)
        x[:2] *= min(1.0, self.step_m / max(float(np.hypot(*x[:2])), 1e-12))
        x[2] = min(max(x[2], -self.step_rad), self.step_rad)
        new = total + x
        new[:2] *= min(1.0, self.total_m / max(float(np.hypot(*new[:2])), 1e-12))
        new[2] = min(max(new[2], -self.total_rad), self.total_rad)
        x = new - total
        # the increment about the laser, as a transform of the map: p -> R (p - c) + c + x[:2]
        cs, sn = math.cos(x[2]), math.sin(x[2])
        step = (
            c[0] - (cs * c[0] - sn * c[1]) + x[0],
            c[1] - (sn * c[0] + cs * c[1]) + x[1],
            float(x[2]),
        )
        self.correction = tuple(float(v) for v in se2.compose(step, self.correction))
        self.information, self.centre_xy_m = info, c
        self.matches += 1
        return step

    def pose_covariance(self, base_xy_m) -> np.ndarray:
        """Covariance (3, 3) of x_m, y_m, yaw_rad of ``base_link`` at ``base_xy_m`` (2,) after the
        last fit: the fit's (the inverse of :attr:`information`, a direction the scan leaves open,
        an aisle's length, stays open) moved from the laser to the base, times
        ``feedback_inflation`` (the returns are not independent: neighbours fall in the same map
        cells), plus ``feedback_floor_*`` squared."""
        cov = np.linalg.inv(self.information + 1e-6 * np.eye(3))
        bx, by = np.asarray(base_xy_m, float) - self.centre_xy_m
        J = np.array([[1.0, 0.0, -by], [0.0, 1.0, bx], [0.0, 0.0, 1.0]])
        return self.feedback_inflation * (J @ cov @ J.T) + np.diag(self.feedback_floor)

    def pose_message(self, pose, stamp_s: float, seq: int) -> PoseWithCovarianceStamped:
        """``pose`` (3,) of ``base_link`` in ``map`` at ``stamp_s`` (the corrected pose of the
        localisation's message of that instant) with :meth:`pose_covariance`."""
        cov6 = np.zeros((6, 6))
        cov6[np.ix_([0, 1, 5], [0, 1, 5])] = self.pose_covariance(pose[:2])
        cov6[2, 2] = cov6[3, 3] = cov6[4, 4] = 1e6  # z, roll, pitch: not measured (two_d_mode)
        return PoseWithCovarianceStamped(
            Header(seq, Time.from_sec(stamp_s), "map"),
            PoseWithCovariance(
                Pose(
                    Point(float(pose[0]), float(pose[1]), 0.0), Quaternion.from_yaw(float(pose[2]))
                ),
                cov6.ravel(),
            ),
        )
