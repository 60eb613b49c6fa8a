"""ROS occupancy maps (map_server YAML + PGM) as MuJoCo worlds of extruded wall boxes.

A map_server map is a YAML file (``image``, ``resolution`` m/pixel, ``origin``
``[x, y, yaw]`` of the lower-left pixel, ``occupied_thresh``, ``free_thresh``,
``negate``, ``mode``) next to a greyscale image. A pixel is occupied when its
occupancy ``p = (255 - v) / 255`` (``v / 255`` with ``negate: 1``) exceeds
``occupied_thresh``, as map_server's ``trinary`` (the default) and ``scale`` modes
read it; in ``raw`` mode the pixel is the occupancy in percent (255 unknown).

Occupied cells become boxes of height ``wall_height_m`` standing on the floor:
runs of occupied cells along each image row are merged, then identical runs in
consecutive rows are merged into one rectangle (never one geom per cell).
:func:`world_xml` writes an MJCF world (floor, light, boxes, all group 0) that
``build(cfg, world="path/to/map.yaml")`` loads. This module does not import mujoco.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from amr_twin.model.pgm import read_pgm
from amr_twin.model.worlds import MapError

WALL_HEIGHT_M = 2.0


@dataclass(frozen=True)
class OccupancyMap:
    """An occupancy grid: ``occupied[row, col]`` with row 0 at the top of the image (max y).

    ``free[row, col]``: the cells map_server reads as free (occupancy below ``free_thresh``); a
    cell neither occupied nor free is unknown.
    """

    occupied: np.ndarray
    resolution_m: float
    origin_xyyaw: tuple[float, float, float]
    free: np.ndarray | None = None


MAX_ORIGIN = 1e4
"""Largest |x|, |y| (m) and |yaw| (rad) of a map's origin (as --start's bound): farther, the world's
floats lose their centimetres."""
MAX_WALL_BOXES = 20_000
"""Most wall boxes (MuJoCo geoms) of a map's world: 4 times a SLAM map of the aisles world (4894);
45,000 (a 300 x 300 checkerboard) took 9 s to build and check, a 1500 x 1500 one did not end in 60
s."""
MAX_WALL_RUNS = 1_000_000
"""Most runs of occupied cells (along the rows) a map's walls are merged from (the merge loops over
them)."""
MAP_MODES = ("trinary", "scale", "raw")
"""map_server's ``mode`` values (trinary when absent); trinary and scale give the same walls."""


def _map_number(
    path,
    meta: dict,
    key: str,
    default=None,
    low: float | None = None,
    high: float | None = None,
    open_low: bool = False,
) -> float:
    value = meta.get(key, default)
    if value is None:
        raise MapError(
            f"{path}: {key} is missing (map_server YAML: image, resolution, origin, ...)"
        )
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise MapError(f"{path}: {key}: {value!r} must be a finite number")
    if (low is not None and (value <= low if open_low else value < low)) or (
        high is not None and value > high
    ):
        bound = (
            f"{'(' if open_low else '['}{low:g}, {high:g}]" if high is not None else f"> {low:g}"
        )
        raise MapError(f"{path}: {key}: {value} must be in {bound}")
    return float(value)


def load_map(yaml_path: str | Path) -> OccupancyMap:
    """Load a map_server YAML and its image into an :class:`OccupancyMap`.

    Raises :class:`MapError` (one line naming the YAML or the image) when a field is
    missing or out of range, or the image cannot be read.
    """
    from amr_twin.model.yaml_file import read_yaml

    yaml_path = Path(yaml_path)
    meta = read_yaml(yaml_path, "map", MapError)
    if not isinstance(meta, dict):
        raise MapError(
            f"{yaml_path}: expected a map_server mapping (image, resolution, origin, ...)"
        )
    mode = meta.get("mode", "trinary")
    if mode not in MAP_MODES:
        raise MapError(
            f"{yaml_path}: mode {mode!r} is not one of {', '.join(MAP_MODES)} (map_server)"
        )
    image_name = meta.get("image")
    if not isinstance(image_name, str) or not image_name:
        raise MapError(f"{yaml_path}: image is missing (the PGM file name, relative to the YAML)")
    resolution = _map_number(yaml_path, meta, "resolution", low=0.0, high=100.0, open_low=True)
    origin = meta.get("origin", [0.0, 0.0, 0.0])
    if (
        not isinstance(origin, (list, tuple))
        or len(origin) != 3
        or not all(
            isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)
            for v in origin
        )
    ):
        raise MapError(
            f"{yaml_path}: origin: {origin!r} must be [x_m, y_m, yaw_rad], three finite numbers"
        )
    if not all(abs(v) <= MAX_ORIGIN for v in origin):
        raise MapError(
            f"{yaml_path}: origin: {origin!r}: each value must lie within +-{MAX_ORIGIN:g} (m, "
            f"m, rad)"
        )
    origin = tuple(float(v) for v in origin)
    occupied = _map_number(yaml_path, meta, "occupied_thresh", 0.65, 0.0, 1.0)
    free = _map_number(yaml_path, meta, "free_thresh", 0.196, 0.0, 1.0)
    if free >= occupied:
        raise MapError(
            f"{yaml_path}: free_thresh {free:g} must be below occupied_thresh {occupied:g} "
            f"(map_server)"
        )
    negate = meta.get("negate", 0)
    if negate not in (0, 1, True, False):
        raise MapError(f"{yaml_path}: negate: {negate!r} must be 0 or 1")
    try:
        image = read_pgm(yaml_path.parent / image_name)
    except MapError as exc:
        raise MapError(f"{yaml_path}: image {exc}") from None
    if mode == "raw":  # the pixel is the occupancy in percent (255 unknown)
        known = image != 255
        return OccupancyMap(
            known & (image / 100.0 > occupied), resolution, origin, known & (image / 100.0 < free)
        )
    p = image / 255.0 if int(negate) else (255 - image.astype(float)) / 255.0
    return OccupancyMap(p > occupied, resolution, origin, p < free)


def merge_boxes(occupied: np.ndarray) -> list[tuple[int, int, int, int]]:
    """Cover the occupied cells with rectangles ``(row0, col0, n_rows, n_cols)``.

    Runs along each row are merged, then a run continues the rectangle above it
    when it spans exactly the same columns. The rectangles do not overlap.
    """
    open_rects: dict[tuple[int, int], list[int]] = {}  # (col0, col1) -> [row0, n_rows]
    done: list[tuple[int, int, int, int]] = []
    for r, row in enumerate(np.asarray(occupied, bool)):
        padded = np.concatenate(([False], row, [False]))
        edges = np.flatnonzero(padded[1:] != padded[:-1])
        runs = set(zip(edges[0::2].tolist(), edges[1::2].tolist()))
        for key in list(open_rects):
            if key in runs:
                open_rects[key][1] += 1
                runs.discard(key)
            else:
                row0, n = open_rects.pop(key)
                done.append((row0, key[0], n, key[1] - key[0]))
        for key in runs:
            open_rects[key] = [r, 1]
    done.extend((row0, c0, n, c1 - c0) for (c0, c1), (row0, n) in open_rects.items())
    return sorted(done)


def wall_boxes(
    grid: OccupancyMap, wall_height_m: float = WALL_HEIGHT_M
) -> list[tuple[np.ndarray, np.ndarray, float]]:
    """Boxes ``(centre_xyz (3,), half_size (3,), yaw_rad)`` in the world frame, m."""
    res, (ox, oy, yaw) = grid.resolution_m, grid.origin_xyyaw
    rows = grid.occupied.shape[0]
    c, s = math.cos(yaw), math.sin(yaw)
    boxes = []
    for row0, col0, n_rows, n_cols in merge_boxes(grid.occupied):
        # map frame: x along columns, y up from the bottom row (image row rows-1)
        mx = (col0 + n_cols / 2) * res
        my = (rows - row0 - n_rows / 2) * res
        centre = np.array([ox + c * mx - s * my, oy + s * mx + c * my, wall_height_m / 2])
        boxes.append(
            (centre, np.array([n_cols * res / 2, n_rows * res / 2, wall_height_m / 2]), yaw)
        )
    return boxes


def world_xml(yaml_path: str | Path, wall_height_m: float = WALL_HEIGHT_M) -> str:
    """MJCF text of the map's world: floor, light and merged wall boxes (group 0)."""
    grid = load_map(yaml_path)
    rows, cols = grid.occupied.shape
    padded = np.pad(grid.occupied, ((0, 0), (1, 0))).astype(np.int8)
    runs = int(
        np.count_nonzero(np.diff(padded, axis=1) == 1)
    )  # counted before the merge, which loops over them
    if runs > MAX_WALL_RUNS:
        raise MapError(
            f"{yaml_path}: {runs:,} runs of occupied cells; at most {MAX_WALL_RUNS:,} (a map this "
            "fragmented, noise or a checkerboard, would be a world of too many walls)"
        )
    boxes = wall_boxes(grid, wall_height_m)
    if len(boxes) > MAX_WALL_BOXES:
        raise MapError(
            f"{yaml_path}: {len(boxes):,} wall boxes after merging its occupied cells; at most "
            f"{MAX_WALL_BOXES:,} (each is a MuJoCo geom: 45,000 took 9 s to build; a SLAM map of "
            f"the aisles "
            "world has about 5,000)"
        )
    span = (
        max(rows, cols) * grid.resolution_m + abs(grid.origin_xyyaw[0]) + abs(grid.origin_xyyaw[1])
    )
    lines = [
        f'<mujoco model="{Path(yaml_path).stem}">',
        "  <worldbody>",
        '    <light name="sun" pos="0 0 8" dir="0 0 -1" directional="true"/>',
        f'    <geom name="floor" type="plane" size="{span:.3f} {span:.3f} 0.1" rgba="0.55 0.55 '
        f'0.55 1"/>',
    ]
    for i, (centre, half, yaw) in enumerate(boxes):
        pos = " ".join(f"{v:.6g}" for v in centre)
        size = " ".join(f"{v:.6g}" for v in half)
        lines.append(
            f'    <geom name="wall_{i}" type="box" pos="{pos}" size="{size}" '
            f'euler="0 0 {math.degrees(yaw):.6g}" rgba="0.85 0.84 0.80 1"/>'
        )
    lines += ["  </worldbody>", "</mujoco>", ""]
    return "\n".join(lines)
