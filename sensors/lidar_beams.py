"""Beams of the RPLIDAR A1: timing, directions, laser pose samples, range noise.

Pure numpy (no MuJoCo, no clock): the clock-driven sensor that casts the beams is
:class:`amr_twin.sensors.lidar.Lidar`.

Reasons and measurements: docs/explanation/lidar.md#amr_twinsensorslidar_beams.

Part of the physics layer (``PHYSICS_LAYER``): keeps the laser site's pose from MjData on the loop's
grid (views of ``site_xpos``/``site_xmat``)."""

from __future__ import annotations

import math

import numpy as np

from amr_twin.model.config_sensors import LidarCfg
from amr_twin.sim.grid_rows import GridRows, gather
from amr_twin.base.native_build import address

PHYSICS_LAYER = True

US = 1_000_000
SEEN_GROUPS = (0, 4)
"""Geom groups a beam can hit: world and payload (build.py)."""


def scan_timing(cfg: LidarCfg) -> tuple[int, int, int]:
    """``(n_beams, beam_dt_us, scan_us)``: beams per rotation, time between beams and per rotation,
    us."""
    n_beams = int(round(cfg.sample_rate_hz / cfg.scan_rate_hz))
    beam_dt_us = US // cfg.sample_rate_hz
    return n_beams, beam_dt_us, n_beams * beam_dt_us


def beam_angles_rad(n_beams: int) -> tuple[float, float, np.ndarray]:
    """``(angle_min, angle_increment, angles)`` of ``n_beams`` beams over a turn, rad; angles shape
    (n_beams,)."""
    angle_increment = 2 * math.pi / n_beams
    angle_min = -math.pi
    return angle_min, angle_increment, angle_min + angle_increment * np.arange(n_beams)


def beam_times_s(scan) -> np.ndarray:
    """Acquisition time of every beam of a ``LaserScan``, s, shape (n,): ``stamp + i *
    time_increment``."""
    return scan.header.stamp.to_sec() + scan.time_increment * np.arange(len(scan.ranges))


def scan_end_time_s(scan) -> float:
    """Time of a ``LaserScan``'s last acquired beam, s (its stamp when ``time_increment <= 0``)."""
    return scan.header.stamp.to_sec() + max(scan.time_increment * max(len(scan.ranges) - 1, 0), 0.0)


def beam_directions(angles_rad: np.ndarray) -> np.ndarray:
    """Unit directions of beams at ``angles_rad`` (n,) in the laser frame, shape (n, 3) (z = 0)."""
    return np.stack([np.cos(angles_rad), np.sin(angles_rad), np.zeros(len(angles_rad))], axis=1)


def group_masks(
    geom_group: np.ndarray, geom_moving: np.ndarray
) -> tuple[np.ndarray, np.ndarray | None, np.ndarray | None]:
    """``mj_multiRay`` geom group masks (6,) uint8: ``(seen, world, payload)``.

    Parameters
    ----------
    geom_group : ndarray, shape (ngeom,), int
        Group of each geom (``MjModel.geom_group``).
    geom_moving : ndarray, shape (ngeom,), bool
        Whether each geom moves with a free body (the robot).

    Returns
    -------
    seen : ndarray, shape (6,)
        Every group of :data:`SEEN_GROUPS`.
    world, payload : ndarray, shape (6,), or None
        With a payload geom that moves with the robot: the world group alone and the
        payload group alone (cast apart, the payload in the present laser frame);
        otherwise None.
    """
    seen = np.zeros(6, np.uint8)
    seen[list(SEEN_GROUPS)] = 1
    payload = (geom_group == SEEN_GROUPS[1]) & geom_moving
    if not payload.any():
        return seen, None, None
    world = np.zeros(6, np.uint8)
    world[SEEN_GROUPS[0]] = 1
    payload_groups = np.zeros(6, np.uint8)
    payload_groups[SEEN_GROUPS[1]] = 1
    return seen, world, payload_groups


class PoseSamples(GridRows):
    """Laser pose samples: rows of ``t_us``, position (3, m), laser x axis and y axis in the world
    (3 + 3).

    A :class:`~amr_twin.sim.grid_rows.GridRows` of the laser site's ``site_xpos`` and
    ``site_xmat`` (``data``, ``site_id``) every ``period_us``: kept by the loop's grid (in C,
    ``gs_gather``, when the loop runs its grid there) or by the sensor's clock events;
    ``after(t_us)`` runs after a sample at or after :attr:`due_us` (the casts). ``native=False``:
    Python only.
    """

    def __init__(self, data, site_id: int, period_us: int, after, native: bool = True):
        pos, mat = (
            data.site_xpos[site_id],
            data.site_xmat[site_id],
        )  # views: MjData's buffers stay put

        def row() -> list[float]:
            x, y, z = pos.tolist()
            m = mat.tolist()
            return [x, y, z, m[0], m[3], m[6], m[1], m[4], m[7]]  # the laser x axis, y axis

        at = address(data.site_xpos) + 8 * 3 * site_id, address(data.site_xmat) + 8 * 9 * site_id
        c_row = (
            gather([at[0] + 8 * k for k in range(3)] + [at[1] + 8 * k for k in (0, 3, 6, 1, 4, 7)])
            if native
            else None
        )
        super().__init__(9, period_us, row, c_row, after=after)

    @property
    def rows(self) -> np.ndarray:
        """The samples, shape (n, 10), float64 (at least one row: zeros when there is none)."""
        return super().rows if self.n else np.zeros((1, 10))

    def keep_from(self, t_us: int) -> None:
        """Forget the samples that no instant at or after ``t_us`` needs: all before the last one at
        or before ``t_us`` (the beams of a rotation that began before the newest sample are
        interpolated from the sample before them, not held at the newest)."""
        n = self.n
        k = max(int(np.searchsorted(self._buf[:n, 0], t_us, side="right")) - 1, 0)
        if k:
            self._buf[: n - k] = self._buf[k:n]
            self._set_n(n - k)


def interpolate_poses(rows: np.ndarray, n: int, t_us: np.ndarray) -> np.ndarray:
    """Poses (k, 9) at the instants ``t_us`` (k,) from the first ``n`` sample ``rows`` of
    :class:`PoseSamples`.

    Linear between the two samples around each instant, held outside them (the first
    row alone when ``n < 2``): position (m), laser x axis, laser y axis.
    """
    if n < 2:
        return np.repeat(rows[0:1, 1:], len(t_us), axis=0)
    ts = rows[:n, 0]
    j = np.minimum(np.maximum(ts.searchsorted(t_us, side="right") - 1, 0), n - 2)
    t0 = ts[j]
    a = np.minimum(np.maximum((t_us - t0) / (ts[j + 1] - t0), 0.0), 1.0)[:, None]
    p0 = rows[j, 1:]
    return p0 + a * (rows[j + 1, 1:] - p0)


def world_directions(pose: np.ndarray, lx: np.ndarray, ly: np.ndarray) -> np.ndarray:
    """Unit beam directions in the world (k, 3) from laser poses (k, 9) and laser-frame components
    (k, 1) x 2."""
    u = pose[:, 3:6] * lx + pose[:, 6:9] * ly  # R l with l_z = 0
    u /= np.sqrt(u[:, 0] * u[:, 0] + u[:, 1] * u[:, 1] + u[:, 2] * u[:, 2])[
        :, None
    ]  # the C helper's order
    return u


def noisy_ranges(
    dist: np.ndarray, geomid: np.ndarray, cfg: LidarCfg, rng: np.random.Generator
) -> np.ndarray:
    """Range noise, 1/4 mm quantisation and validity of true distances.

    Parameters
    ----------
    dist : ndarray, shape (n,)
        True distances, m (any value where ``geomid < 0``).
    geomid : ndarray, shape (n,), int
        Geom hit by each beam, -1 for none.
    cfg : LidarCfg
        Noise, resolution and range limits.
    rng : numpy.random.Generator
        Draws the noise (n standard normals).

    Returns
    -------
    ndarray, shape (n,), float32
        Ranges, m; inf where nothing was hit or out of ``[range_min, range_max]``.
    """
    return quantised_ranges(dist, geomid, rng.standard_normal(len(dist)), cfg)


def quantised_ranges(
    dist: np.ndarray, geomid: np.ndarray, z: np.ndarray, cfg: LidarCfg
) -> np.ndarray:
    """:func:`noisy_ranges` with the ``n`` standard normals ``z`` (n,) given: ranges (n,) float32,
    m."""
    sigma = np.maximum(cfg.range_noise_floor_m, cfg.range_noise_frac * dist)
    r = dist + sigma * z
    if cfg.range_resolution_m > 0:
        r = np.round(r / cfg.range_resolution_m) * cfg.range_resolution_m
    valid = (geomid >= 0) & (r >= cfg.range_min_m) & (r <= cfg.range_max_m)
    return np.where(valid, r, np.inf).astype(np.float32)
