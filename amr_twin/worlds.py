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
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import yaml

from .paths import ROOT

WALL_HEIGHT_M = 2.0
WORLD_DIR = ROOT / "models" / "worlds"
START_NUMERIC = "start_xy_yaw"
"""Name of an MJCF ``<custom><numeric>`` holding a world's default start pose: x_m y_m yaw_rad."""


def world_path(world: str | Path) -> Path:
    """The file of ``world``: a name of ``models/worlds/`` (``warehouse``, ``empty``) or a path."""
    path = Path(world)
    return WORLD_DIR / f"{world}.xml" if not path.suffix else path


def default_start(world: str | Path) -> tuple[float, float, float]:
    """The world's start pose ``(x_m, y_m, yaw_rad)``: its ``start_xy_yaw`` numeric, else the origin.

    Only MJCF worlds can declare one (``<custom><numeric name="start_xy_yaw" data="x y yaw"/>``);
    a file that cannot be read gives the origin (the model build reports the error).
    """
    path = world_path(world)
    if path.suffix.lower() != ".xml":
        return (0.0, 0.0, 0.0)
    try:
        root = ET.parse(path).getroot()
    except (OSError, ET.ParseError):
        return (0.0, 0.0, 0.0)
    for numeric in root.iter("numeric"):
        if numeric.get("name") == START_NUMERIC:
            try:
                x, y, yaw = (float(v) for v in (numeric.get("data") or "").split())
            except ValueError:
                break
            return (x, y, yaw)
    return (0.0, 0.0, 0.0)


@dataclass(frozen=True)
class OccupancyMap:
    """An occupancy grid: ``occupied[row, col]`` with row 0 at the top of the image (max y)."""

    occupied: np.ndarray
    resolution_m: float
    origin_xyyaw: tuple[float, float, float]


def read_pgm(path: str | Path) -> np.ndarray:
    """Read a binary (P5) or ASCII (P2) 8-bit PGM image as a (rows, cols) uint8 array."""
    data = Path(path).read_bytes()
    tokens: list[bytes] = []
    pos = 0
    while len(tokens) < 4:  # magic, width, height, maxval (comments start with #)
        while data[pos:pos + 1].isspace():
            pos += 1
        if data[pos:pos + 1] == b"#":
            pos = data.index(b"\n", pos) + 1
            continue
        end = pos
        while not data[end:end + 1].isspace():
            end += 1
        tokens.append(data[pos:end])
        pos = end
    magic, width, height, maxval = tokens[0], int(tokens[1]), int(tokens[2]), int(tokens[3])
    if maxval > 255:
        raise ValueError(f"{path}: only 8-bit PGM is supported (maxval {maxval})")
    if magic == b"P5":
        pixels = np.frombuffer(data, np.uint8, width * height, pos + 1)
    elif magic == b"P2":
        pixels = np.array(data[pos:].split(), dtype=np.uint8)[:width * height]
    else:
        raise ValueError(f"{path}: not a PGM image (magic {magic!r})")
    return pixels.reshape(height, width).copy()


def write_pgm(path: str | Path, image: np.ndarray) -> None:
    """Write a (rows, cols) uint8 array as a binary P5 PGM."""
    image = np.asarray(image, np.uint8)
    Path(path).write_bytes(b"P5\n%d %d\n255\n" % (image.shape[1], image.shape[0]) + image.tobytes())


MAP_MODES = ("trinary", "scale", "raw")
"""map_server's ``mode`` values (trinary when absent); trinary and scale give the same walls."""


def load_map(yaml_path: str | Path) -> OccupancyMap:
    """Load a map_server YAML and its image into an :class:`OccupancyMap`."""
    yaml_path = Path(yaml_path)
    meta = yaml.safe_load(yaml_path.read_text())
    mode = meta.get("mode", "trinary")
    if mode not in MAP_MODES:
        raise ValueError(f"{yaml_path}: mode {mode!r} is not one of {', '.join(MAP_MODES)} (map_server)")
    image = read_pgm(yaml_path.parent / meta["image"])
    if mode == "raw":  # the pixel is the occupancy in percent (255 unknown)
        return OccupancyMap((image != 255) & (image / 100.0 > float(meta.get("occupied_thresh", 0.65))),
                            float(meta["resolution"]), tuple(float(v) for v in meta.get("origin", (0.0, 0.0, 0.0))))
    p = image / 255.0 if int(meta.get("negate", 0)) else (255 - image.astype(float)) / 255.0
    origin = tuple(float(v) for v in meta.get("origin", (0.0, 0.0, 0.0)))
    return OccupancyMap(p > float(meta.get("occupied_thresh", 0.65)), float(meta["resolution"]),
                        origin)


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


def wall_boxes(grid: OccupancyMap, wall_height_m: float = WALL_HEIGHT_M) -> list[tuple[np.ndarray, np.ndarray, float]]:
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
        boxes.append((centre, np.array([n_cols * res / 2, n_rows * res / 2, wall_height_m / 2]), yaw))
    return boxes


def world_xml(yaml_path: str | Path, wall_height_m: float = WALL_HEIGHT_M) -> str:
    """MJCF text of the map's world: floor, light and merged wall boxes (group 0)."""
    grid = load_map(yaml_path)
    rows, cols = grid.occupied.shape
    span = max(rows, cols) * grid.resolution_m + abs(grid.origin_xyyaw[0]) + abs(grid.origin_xyyaw[1])
    lines = [f'<mujoco model="{Path(yaml_path).stem}">', "  <worldbody>",
             '    <light name="sun" pos="0 0 8" dir="0 0 -1" directional="true"/>',
             f'    <geom name="floor" type="plane" size="{span:.3f} {span:.3f} 0.1" rgba="0.55 0.55 0.55 1"/>']
    for i, (centre, half, yaw) in enumerate(wall_boxes(grid, wall_height_m)):
        pos = " ".join(f"{v:.6g}" for v in centre)
        size = " ".join(f"{v:.6g}" for v in half)
        lines.append(f'    <geom name="wall_{i}" type="box" pos="{pos}" size="{size}" '
                     f'euler="0 0 {math.degrees(yaw):.6g}" rgba="0.85 0.84 0.80 1"/>')
    lines += ["  </worldbody>", "</mujoco>", ""]
    return "\n".join(lines)
