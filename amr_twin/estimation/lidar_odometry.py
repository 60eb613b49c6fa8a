"""LiDAR odometry: KISS-ICP (1.3) on ``sensor_msgs/LaserScan`` with a wheel-odometry prior.

Each scan becomes an (N, 3) cloud with z = 0 in the ``laser`` frame (beam ``i``
at ``angle_min + i * angle_increment``; inf, NaN and out-of-range beams dropped)
and is registered with :class:`kiss_icp.kiss_icp.KissICP` (its preprocessing,
deskew, voxel map, adaptive threshold and point-to-point ICP, nothing
re-implemented here).

Reasons and measurements: docs/explanation/fusion.md#amr_twinestimationlidar_odometry."""

from __future__ import annotations

import math
import time

import numpy as np
from kiss_icp.config import KISSConfig
from kiss_icp.kiss_icp import KissICP

from amr_twin.ros.sensor_messages import LaserScan
from amr_twin.analysis import se2
from amr_twin.sensors.lidar_beams import beam_times_s, scan_end_time_s  # noqa: F401 (part of this API)

MIN_POINTS = 20
"""Fewest valid beams a scan needs to be registered."""
SENTINEL_RANGE_M = 1.0e6
"""Range of the two timing sentinel points (beyond any max range: never registered)."""


def scan_points(scan: LaserScan) -> tuple[np.ndarray, np.ndarray]:
    """Valid beams as points in the laser frame and their beam indices.

    Returns
    -------
    points : ndarray, shape (k, 3)
        ``x, y, 0`` in metres, laser frame (REP-103).
    index : ndarray, shape (k,), int
        Beam index of each point (finite range within ``[range_min, range_max]``).
    """
    r = np.asarray(scan.ranges, np.float64)
    with np.errstate(invalid="ignore"):
        ok = np.isfinite(r) & (r >= scan.range_min) & (r <= scan.range_max)
    index = np.flatnonzero(ok)
    angle = scan.angle_min + scan.angle_increment * index
    points = np.column_stack(
        [r[index] * np.cos(angle), r[index] * np.sin(angle), np.zeros(len(index))]
    )
    return points, index


class LidarOdometry:
    """KISS-ICP scan-to-map odometry of ``base_link`` from 2D laser scans.

    Parameters
    ----------
    voxel_size_m : float
        KISS-ICP map voxel size, m, in (0, 1] (0.1 to 0.25 works for a 12 m 2D scanner;
        0.05 diverged, stack-notes.md).
    max_range_m, min_range_m : float
        Points outside ``(min_range_m, max_range_m)`` are dropped, m.
    laser_in_base_xy_yaw : tuple of 3 float
        Pose of ``laser`` in ``base_link`` (m, m, rad); the twin's is (0.30, 0, 0).
    deskew : bool
        Motion-compensate each scan with its per-beam timestamps.
    max_threads : int
        KISS-ICP worker threads (0: as many as cores).
    """

    def __init__(
        self,
        *,
        voxel_size_m: float = 0.15,
        max_range_m: float = 12.0,
        min_range_m: float = 0.15,
        laser_in_base_xy_yaw: tuple[float, float, float] = (0.30, 0.0, 0.0),
        deskew: bool = True,
        max_threads: int = 1,
    ):
        if not (math.isfinite(voxel_size_m) and 0.0 < voxel_size_m <= 1.0):
            raise ValueError(f"voxel_size_m: {voxel_size_m} must lie in (0, 1] m")
        if not (math.isfinite(max_range_m) and 0.0 <= min_range_m < max_range_m):
            raise ValueError(
                f"min_range_m, max_range_m: ({min_range_m}, {max_range_m}) must satisfy "
                "0 <= min_range_m < max_range_m < inf"
            )
        if len(laser_in_base_xy_yaw) != 3 or not all(
            math.isfinite(v) for v in laser_in_base_xy_yaw
        ):
            raise ValueError(
                f"laser_in_base_xy_yaw: {laser_in_base_xy_yaw} must be 3 finite numbers"
            )
        if int(max_threads) < 0:
            raise ValueError(f"max_threads: {max_threads} must be >= 0")
        config = KISSConfig()
        config.mapping.voxel_size = float(voxel_size_m)
        config.data.max_range, config.data.min_range = float(max_range_m), float(min_range_m)
        config.data.deskew = bool(deskew)
        config.registration.max_num_threads = int(max_threads)
        self.config = config
        self.kiss = KissICP(config)
        self.laser_in_base_xy_yaw = tuple(float(v) for v in laser_in_base_xy_yaw)
        self._laser = se2.matrix(*self.laser_in_base_xy_yaw)
        self._laser_inv = np.linalg.inv(self._laser)
        self._t_s: list[float] = []
        self._poses: list[tuple[float, float, float]] = []
        self.register_wall_s: list[float] = []
        """Wall time of each :meth:`register` call, s."""
        self.skipped = 0
        """Scans with fewer than :data:`MIN_POINTS` valid beams (not registered)."""

    def prior_interval_s(self, scan: LaserScan) -> tuple[float, float]:
        """Interval ``(t0_s, t1_s)`` over which :meth:`register` wants the motion prior of ``scan``.

        ``t1_s`` is the scan's ``t_end``; ``t0_s`` the previous scan's ``t_end``, or, for the
        first scan, ``t_end - scan_time`` (one rotation: the first scan is deskewed too).
        """
        t_end = scan_end_time_s(scan)
        if self._t_s:
            return self._t_s[-1], t_end
        period_s = (
            scan.scan_time if scan.scan_time > 0 else len(scan.ranges) * abs(scan.time_increment)
        )
        t0 = min(t_end - period_s, float(beam_times_s(scan).min()) if len(scan.ranges) else t_end)
        return (t0 if t0 < t_end else t_end - 1e-3), t_end

    def register(
        self, scan: LaserScan, prior_base_delta: tuple[float, float, float] | None = None
    ) -> tuple[float, float, float]:
        """Register one scan; return the ``base_link`` pose at its last beam.

        Parameters
        ----------
        scan : LaserScan
            Scan in the ``laser`` frame; scans must come in time order.
        prior_base_delta : tuple (dx_m, dy_m, dyaw_rad) or None
            Motion of ``base_link`` over :meth:`prior_interval_s` (from the previous scan's
            ``t_end`` to this scan's), in the earlier ``base_link`` frame. For the first scan
            it only deskews it (the first pose is the origin); None there: not deskewed.

        Returns
        -------
        tuple (x_m, y_m, yaw_rad)
            ``base_link`` pose in the odometry frame of the first scan.
        """
        wall0 = time.perf_counter()
        t_start, t_end = self.prior_interval_s(scan)
        first = not self._t_s
        if not first and t_end <= t_start:
            raise ValueError(
                f"scan stamp: t_end {t_end:.6f} s must be after the previous {t_start:.6f} s"
            )
        delta = None
        if prior_base_delta is not None:
            if len(prior_base_delta) != 3 or not all(math.isfinite(v) for v in prior_base_delta):
                raise ValueError(
                    f"prior_base_delta: {prior_base_delta} must be 3 finite numbers (m, m, rad)"
                )
            delta = (
                self._laser_inv @ se2.matrix(*(float(v) for v in prior_base_delta)) @ self._laser
            )
        if first:  # deskew along the prior, but start at the origin: initial guess inv(D) @ D = I
            self.kiss.last_delta = delta if delta is not None else np.eye(4)
            self.kiss.last_pose = np.linalg.inv(self.kiss.last_delta)
        elif delta is not None:
            self.kiss.last_delta = delta
        points, index = scan_points(scan)
        if len(index) >= MIN_POINTS:
            stamps = scan.header.stamp.to_sec() + scan.time_increment * index
            sentinel = np.array([[SENTINEL_RANGE_M, 0.0, 0.0]] * 2)
            self.kiss.register_frame(
                np.vstack([points, sentinel]), np.concatenate([stamps, [t_start, t_end]])
            )
        else:  # too few points: carry the pose forward along the prior
            self.skipped += 1
            self.kiss.last_pose = self.kiss.last_pose @ self.kiss.last_delta
        pose = se2.from_matrix(self._laser @ self.kiss.last_pose @ self._laser_inv)
        self._t_s.append(t_end)
        self._poses.append(pose)
        self.register_wall_s.append(time.perf_counter() - wall0)
        return pose

    def poses(
        self, origin_xy_yaw: tuple[float, float, float] | None = None
    ) -> tuple[np.ndarray, np.ndarray]:
        """History of the estimates.

        Parameters
        ----------
        origin_xy_yaw : tuple of 3 float, optional
            Pose of the first estimate in another frame (e.g. the true pose at the first
            scan's ``t_end`` in the world); every pose is then returned in that frame.

        Returns
        -------
        t_s : ndarray, shape (N,)
            ``t_end`` of each registered scan, s (the stamp each pose holds at).
        pose : ndarray, shape (N, 3)
            ``base_link`` ``x_m, y_m, yaw_rad``.
        """
        pose = np.array(self._poses, float).reshape(-1, 3)
        if origin_xy_yaw is not None:
            pose = se2.compose(np.asarray(origin_xy_yaw, float), pose).reshape(-1, 3)
        return np.array(self._t_s, float), pose

    def beam_laser_poses(
        self, scan: LaserScan, origin_xy_yaw: tuple[float, float, float] | None = None
    ) -> np.ndarray:
        """``laser`` pose at every beam of a registered scan, for mapping a moving scan.

        The ``base_link`` poses of :meth:`poses` are interpolated (linearly, yaw unwrapped)
        at :func:`beam_times_s` (held before the first estimate), then moved to the laser.

        Returns
        -------
        ndarray, shape (n_beams, 3)
            ``x_m, y_m, yaw_rad`` of the laser, in the frame of :meth:`poses`.
        """
        t_s, pose = self.poses(origin_xy_yaw)
        if len(t_s) == 0:
            raise ValueError("beam_laser_poses: no scan registered yet")
        base = se2.interpolate(t_s, pose, beam_times_s(scan)).reshape(-1, 3)
        return se2.compose(base, np.asarray(self.laser_in_base_xy_yaw))
