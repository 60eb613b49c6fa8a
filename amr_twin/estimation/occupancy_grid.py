"""Log-odds occupancy grid from laser scans at known poses, saved in map_server format.

Cells are ``resolution_m`` squares; cell ``(row, col)`` spans
``origin + (col, row) * resolution_m`` to one cell further (row 0 at the lowest
y, as the map frame; the saved image is flipped so its top row is the highest
y, as map_server reads it). Each cell holds the log-odds ``l = ln(p / (1 - p))``
of being occupied, 0 (p = 0.5) when nothing was seen.

Reasons and measurements: docs/explanation/fusion.md#amr_twinestimationoccupancy_grid."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import yaml

from amr_twin.ros.sensor_messages import LaserScan
from amr_twin.model.pgm import write_pgm

OCCUPIED_THRESH = 0.65
FREE_THRESH = 0.196
PGM_FREE, PGM_OCCUPIED, PGM_UNKNOWN = 254, 0, 205


def _logit(p: float) -> float:
    return math.log(p / (1.0 - p))


class OccupancyGrid:
    """A 2D log-odds occupancy grid in the map frame.

    Parameters
    ----------
    resolution_m : float
        Cell side, m (> 0).
    width_m, height_m : float
        Extent along x and y, m (> 0); rounded up to whole cells.
    origin_xy_m : tuple of 2 float
        Map-frame position of the lower-left corner of cell (0, 0), m.
    hit_prob, miss_prob : float
        Inverse sensor model: occupancy probability given a hit (in (0.5, 1)) and given a
        beam through the cell (in (0, 0.5)).
    clamp_prob : tuple of 2 float
        Probability bounds of a cell (``0 < low < 0.5 < high < 1``), so that the map can change.
    free_on_no_return : bool
        Trace beams without a return as free up to ``range_max``.
    """

    def __init__(
        self,
        resolution_m: float,
        width_m: float,
        height_m: float,
        origin_xy_m: tuple[float, float],
        *,
        hit_prob: float = 0.7,
        miss_prob: float = 0.4,
        clamp_prob: tuple[float, float] = (0.12, 0.97),
        free_on_no_return: bool = False,
    ):
        for name, value in (
            ("resolution_m", resolution_m),
            ("width_m", width_m),
            ("height_m", height_m),
        ):
            if not (math.isfinite(value) and value > 0):
                raise ValueError(f"{name}: {value} must be a finite number > 0 m")
        if len(origin_xy_m) != 2 or not all(math.isfinite(v) for v in origin_xy_m):
            raise ValueError(f"origin_xy_m: {origin_xy_m} must be 2 finite numbers (m)")
        if not 0.5 < hit_prob < 1.0:
            raise ValueError(f"hit_prob: {hit_prob} must lie in (0.5, 1)")
        if not 0.0 < miss_prob < 0.5:
            raise ValueError(f"miss_prob: {miss_prob} must lie in (0, 0.5)")
        if not 0.0 < clamp_prob[0] < 0.5 < clamp_prob[1] < 1.0:
            raise ValueError(f"clamp_prob: {clamp_prob} must satisfy 0 < low < 0.5 < high < 1")
        self.resolution_m = float(resolution_m)
        self.origin_xy_m = (float(origin_xy_m[0]), float(origin_xy_m[1]))
        self.n_cols = int(math.ceil(width_m / resolution_m - 1e-9))
        self.n_rows = int(math.ceil(height_m / resolution_m - 1e-9))
        self.l_occ, self.l_free = _logit(hit_prob), _logit(miss_prob)
        self.l_min, self.l_max = _logit(clamp_prob[0]), _logit(clamp_prob[1])
        self.free_on_no_return = bool(free_on_no_return)
        self.log_odds = np.zeros((self.n_rows, self.n_cols), np.float32)
        """Log-odds of occupancy, shape (n_rows, n_cols), row 0 at the lowest y."""
        self._touched = np.zeros(self.n_rows * self.n_cols, bool)
        self._hit = np.zeros(self.n_rows * self.n_cols, bool)
        self.scans_inserted = 0

    # -- geometry -------------------------------------------------------------------
    def cell_index(self, xy_m: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Cells holding map-frame points.

        Parameters
        ----------
        xy_m : ndarray, shape (n, 2)

        Returns
        -------
        row, col : ndarray, shape (n,), int
        inside : ndarray, shape (n,), bool
            The point lies on the grid.
        """
        xy_m = np.asarray(xy_m, float).reshape(-1, 2)
        col = np.floor((xy_m[:, 0] - self.origin_xy_m[0]) / self.resolution_m).astype(np.int64)
        row = np.floor((xy_m[:, 1] - self.origin_xy_m[1]) / self.resolution_m).astype(np.int64)
        inside = (col >= 0) & (col < self.n_cols) & (row >= 0) & (row < self.n_rows)
        return row, col, inside

    def cell_centres_xy(self, mask: np.ndarray) -> np.ndarray:
        """Map-frame centres (k, 2), m, of the cells where ``mask`` (n_rows, n_cols) is true."""
        row, col = np.nonzero(mask)
        return np.column_stack(
            [
                self.origin_xy_m[0] + (col + 0.5) * self.resolution_m,
                self.origin_xy_m[1] + (row + 0.5) * self.resolution_m,
            ]
        )

    # -- update ---------------------------------------------------------------------
    def insert_scan(
        self,
        laser_pose_xy_yaw: tuple[float, float, float],
        scan: LaserScan,
        beam_poses: np.ndarray | None = None,
    ) -> None:
        """Update the grid with one scan.

        Parameters
        ----------
        laser_pose_xy_yaw : tuple of 3 float
            Pose of the ``laser`` frame in the map frame (m, m, rad), used for every beam
            when ``beam_poses`` is None.
        scan : LaserScan
            The scan (ranges in m, angles in the laser frame).
        beam_poses : ndarray, shape (n_beams, 3), optional
            Laser pose of each beam at its own instant (a moving robot), map frame.
        """
        r = np.asarray(scan.ranges, np.float64)
        n = len(r)
        if beam_poses is None:
            if len(laser_pose_xy_yaw) != 3 or not all(math.isfinite(v) for v in laser_pose_xy_yaw):
                raise ValueError(f"laser_pose_xy_yaw: {laser_pose_xy_yaw} must be 3 finite numbers")
            poses = np.broadcast_to(np.asarray(laser_pose_xy_yaw, float), (n, 3))
        else:
            poses = np.asarray(beam_poses, float)
            if poses.shape != (n, 3) or not np.isfinite(poses).all():
                raise ValueError(f"beam_poses: shape {poses.shape} must be ({n}, 3) and finite")
        with np.errstate(invalid="ignore"):
            hit = np.isfinite(r) & (r >= scan.range_min) & (r < scan.range_max)
            no_return = ~np.isfinite(r) | (r >= scan.range_max)
        free_len = np.where(hit, r - 0.5 * self.resolution_m, 0.0)
        traced = hit.copy()
        if self.free_on_no_return:
            free_len = np.where(no_return, scan.range_max, free_len)
            traced |= no_return
        theta = poses[:, 2] + scan.angle_min + scan.angle_increment * np.arange(n)
        cos_t, sin_t = np.cos(theta), np.sin(theta)

        step = 0.5 * self.resolution_m
        beams = np.flatnonzero(traced & (free_len > 0))
        counts = np.floor(free_len[beams] / step).astype(np.int64) + 1
        ray = np.repeat(beams, counts)
        first = np.repeat(np.cumsum(counts) - counts, counts)
        dist = (np.arange(len(ray)) - first) * step
        free_xy = np.column_stack(
            [poses[ray, 0] + dist * cos_t[ray], poses[ray, 1] + dist * sin_t[ray]]
        )
        hits = np.flatnonzero(hit)
        hit_xy = np.column_stack(
            [poses[hits, 0] + r[hits] * cos_t[hits], poses[hits, 1] + r[hits] * sin_t[hits]]
        )

        touched, hit_mask = self._touched, self._hit
        row, col, inside = self.cell_index(free_xy)
        touched[row[inside] * self.n_cols + col[inside]] = True
        row, col, inside = self.cell_index(hit_xy)
        hit_cells = row[inside] * self.n_cols + col[inside]
        touched[hit_cells] = True
        hit_mask[hit_cells] = True
        cells = np.flatnonzero(touched)
        flat = self.log_odds.reshape(-1)
        update = np.where(hit_mask[cells], self.l_occ, self.l_free).astype(np.float32)
        flat[cells] = np.clip(flat[cells] + update, self.l_min, self.l_max)
        touched[cells] = False
        hit_mask[cells] = False
        self.scans_inserted += 1

    # -- read -----------------------------------------------------------------------
    def probabilities(self) -> np.ndarray:
        """Occupancy probability of every cell, shape (n_rows, n_cols), row 0 at the lowest y."""
        return 1.0 / (1.0 + np.exp(-self.log_odds.astype(np.float64)))

    def occupied(self, thresh: float = OCCUPIED_THRESH) -> np.ndarray:
        """Cells whose probability exceeds ``thresh``, (n_rows, n_cols) bool."""
        return self.probabilities() > thresh

    def image(self) -> np.ndarray:
        """map_saver trinary image (n_rows, n_cols) uint8, top row = highest y."""
        p = self.probabilities()
        img = np.full(p.shape, PGM_UNKNOWN, np.uint8)
        img[p > OCCUPIED_THRESH] = PGM_OCCUPIED
        img[p < FREE_THRESH] = PGM_FREE
        return img[::-1].copy()

    def save(self, stem: str | Path) -> tuple[Path, Path, Path]:
        """Write ``<stem>.yaml``, ``<stem>.pgm`` (map_server) and ``<stem>.png``.

        Returns
        -------
        tuple of Path
            The YAML, PGM and PNG paths.
        """
        stem = Path(stem)
        stem.parent.mkdir(parents=True, exist_ok=True)
        yaml_path, pgm_path, png_path = (
            stem.parent / (stem.name + ext) for ext in (".yaml", ".pgm", ".png")
        )
        image = self.image()
        write_pgm(pgm_path, image)
        meta = {
            "image": pgm_path.name,
            "resolution": self.resolution_m,
            "origin": [self.origin_xy_m[0], self.origin_xy_m[1], 0.0],
            "mode": "trinary",
            "negate": 0,
            "occupied_thresh": OCCUPIED_THRESH,
            "free_thresh": FREE_THRESH,
        }
        yaml_path.write_text(yaml.safe_dump(meta, sort_keys=False))
        import matplotlib.image

        matplotlib.image.imsave(png_path, image, cmap="gray", vmin=0, vmax=255)
        return yaml_path, pgm_path, png_path
