"""The map of the fusion drive: scans inserted at the LiDAR odometry's poses, judged against the
world.

The grid covers the world's footprints plus ``mapping.margin_m``; each beam goes in
at the laser pose of its own instant (a scan moves ~0.15 m at 0.8 m/s). The map is read back
through the map_server loader (:func:`amr_twin.model.worlds.load_map`), so what is judged
is what a ROS user would load. Agreement: the distance of every occupied cell's
centre to the nearest world footprint at the LiDAR's height, in cells, and the
share of the world's outline seen by the map (outline samples with an occupied
cell within the same tolerance).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from amr_twin.estimation.occupancy_grid import OccupancyGrid
from amr_twin.model.world_geometry import Footprints, distance_to_boxes_m, surface_samples_m
from amr_twin.model.occupancy_map import OccupancyMap, load_map

TOLERANCE_CELLS = 2


@dataclass(frozen=True)
class MapAgreement:
    """How well a map's walls lie on the world's walls."""

    occupied_cells: int
    within_tolerance_frac: float  # occupied cells within TOLERANCE_CELLS of a world footprint
    p95_distance_cells: float
    max_distance_cells: float
    outline_seen_frac: float  # world outline samples (inside the map) with an occupied cell nearby


def build_map(
    scans: list, beam_poses: list, boxes: Footprints, resolution_m: float, margin_m: float
) -> OccupancyGrid:
    """Insert ``scans`` into a new grid, each beam at its own laser pose (``beam_poses[i]``
    (n_beams, 3), map)."""
    c, s = np.abs(np.cos(boxes.yaw_rad)), np.abs(np.sin(boxes.yaw_rad))
    hx, hy = boxes.half_xy_m[:, 0], boxes.half_xy_m[:, 1]
    half_world = np.column_stack(
        [c * hx + s * hy, s * hx + c * hy]
    )  # axis-aligned bounds of each box
    lo = (boxes.centre_xy_m - half_world).min(0) - margin_m
    hi = (boxes.centre_xy_m + half_world).max(0) + margin_m
    grid = OccupancyGrid(
        resolution_m=resolution_m,
        width_m=float(hi[0] - lo[0]),
        height_m=float(hi[1] - lo[1]),
        origin_xy_m=(float(lo[0]), float(lo[1])),
    )
    for scan, poses in zip(scans, beam_poses):
        grid.insert_scan(None, scan, beam_poses=poses)
    return grid


def occupied_centres_m(grid: OccupancyMap) -> np.ndarray:
    """World coordinates (K, 2) of the occupied cells' centres of a loaded map."""
    rows, cols = np.nonzero(grid.occupied)
    n_rows = grid.occupied.shape[0]
    res, (ox, oy, yaw) = grid.resolution_m, grid.origin_xyyaw
    mx, my = (cols + 0.5) * res, (n_rows - rows - 0.5) * res
    c, s = np.cos(yaw), np.sin(yaw)
    return np.column_stack([ox + c * mx - s * my, oy + s * mx + c * my])


def agreement(
    yaml_path: Path, boxes: Footprints, observed_xy_m: np.ndarray | None = None
) -> MapAgreement:
    """Judge the saved map ``yaml_path`` against the world's footprints ``boxes``.

    ``observed_xy_m`` (M, 2), optional: outline samples to count in ``outline_seen_frac``
    (default: every outline sample inside the map).
    """
    grid = load_map(yaml_path)
    res = grid.resolution_m
    cells = occupied_centres_m(grid)
    if len(cells) == 0:
        return MapAgreement(0, 0.0, float("inf"), float("inf"), 0.0)
    dist_cells = distance_to_boxes_m(cells, boxes) / res
    outline = (
        surface_samples_m(boxes, res) if observed_xy_m is None else np.asarray(observed_xy_m, float)
    )
    if len(outline):
        from scipy.spatial import cKDTree

        d_out, _ = cKDTree(cells).query(outline)
        seen = float(np.mean(d_out <= (TOLERANCE_CELLS + 0.5) * res))
    else:
        seen = 0.0
    return MapAgreement(
        occupied_cells=int(len(cells)),
        within_tolerance_frac=float(np.mean(dist_cells <= TOLERANCE_CELLS + 0.5)),
        p95_distance_cells=float(np.percentile(dist_cells, 95)),
        max_distance_cells=float(dist_cells.max()),
        outline_seen_frac=seen,
    )
