"""The static layer's map: a world's obstacles rasterised, or a map_server map read as nav2's
map_server does.

Two sources, one :class:`StaticMap` (row 0 at the lowest y, as the ``map`` frame; cells of
``resolution_m``, cell ``(row, col)`` spanning ``origin + (col, row) * resolution_m`` to one
cell further):

- :func:`world_map`: the world's *true* map. Every geom of the world (group 0, not the floor)
  whose height range meets the robot's, ``[z_low_m, z_high_m]``, is an obstacle: what the
  robot's body or wheels could hit, whether or not the LiDAR's scan plane cuts it (a loose
  pallet 0.15 m tall is on this map, and not on one built from scans). Boxes are rasterised
  exactly (a cell is occupied when the box overlaps it); other shapes by their bounding box.
- :func:`yaml_map`: a map_server YAML + PGM (a map the fusion experiment saved, an imported
  ROS map): occupied, free and unknown cells as map_server's trinary reading gives them.

Part of the physics layer (``PHYSICS_LAYER``): :func:`world_map` forwards a private MjData of a
freshly compiled world to read where its geoms stand; no twin's state is read or written.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from amr_twin.model.world_geometry import Footprints

PHYSICS_LAYER = True

WORLD_GROUP = 0
MARGIN_M = 0.5
"""Free border kept around a world's obstacles on its map, m."""


@dataclass(frozen=True)
class StaticMap:
    """Occupied and unknown cells, (rows, cols) bool each, row 0 at the lowest y."""

    occupied: np.ndarray
    unknown: np.ndarray
    resolution_m: float
    origin_xy_m: tuple[float, float]
    source: str

    @property
    def shape(self) -> tuple[int, int]:
        return self.occupied.shape


def obstacle_boxes(model, z_low_m: float, z_high_m: float) -> Footprints:
    """The world geoms of a compiled ``model`` whose height range meets ``[z_low_m, z_high_m]``.

    Boxes as they are; any other shape (but planes) as its axis-aligned bounding box.
    """
    import mujoco

    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    centre, half, yaw, names = [], [], [], []
    for g in range(model.ngeom):
        if (
            model.geom_group[g] != WORLD_GROUP
            or model.geom_bodyid[g] != 0
            or model.geom_type[g] == mujoco.mjtGeom.mjGEOM_PLANE
        ):
            continue
        R = data.geom_xmat[g].reshape(3, 3)
        pos = data.geom_xpos[g]
        if model.geom_type[g] == mujoco.mjtGeom.mjGEOM_BOX:
            size = model.geom_size[g]
            half_z = np.abs(R[2]) @ size
            h, a = size[:2], math.atan2(R[1, 0], R[0, 0])
        else:  # the model's bounding box (geom_aabb: centre offset, half sizes in the geom's frame)
            aabb = model.geom_aabb[g]
            ext = np.abs(R) @ aabb[3:]
            pos = pos + R @ aabb[:3]
            half_z, h, a = ext[2], ext[:2], 0.0
        if pos[2] + half_z < z_low_m or pos[2] - half_z > z_high_m:
            continue
        centre.append(pos[:2].copy())
        half.append(np.asarray(h, float))
        yaw.append(a)
        names.append(mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_GEOM, g) or f"geom{g}")
    return Footprints(
        np.array(centre).reshape(-1, 2), np.array(half).reshape(-1, 2), np.array(yaw), tuple(names)
    )


def rasterise(
    boxes: Footprints, resolution_m: float, origin_xy_m: tuple[float, float], shape: tuple[int, int]
) -> np.ndarray:
    """Cells (rows, cols) overlapped by any of ``boxes`` (a cell's centre within the box grown by
    half a cell)."""
    occ = np.zeros(shape, bool)
    res = resolution_m
    for (cx, cy), (hx, hy), a in zip(boxes.centre_xy_m, boxes.half_xy_m, boxes.yaw_rad):
        c, s = math.cos(a), math.sin(a)
        ex, ey = abs(c) * hx + abs(s) * hy, abs(s) * hx + abs(c) * hy
        c0 = max(int(math.floor((cx - ex - origin_xy_m[0]) / res)), 0)
        c1 = min(int(math.ceil((cx + ex - origin_xy_m[0]) / res)), shape[1])
        r0 = max(int(math.floor((cy - ey - origin_xy_m[1]) / res)), 0)
        r1 = min(int(math.ceil((cy + ey - origin_xy_m[1]) / res)), shape[0])
        if c0 >= c1 or r0 >= r1:
            continue
        x = origin_xy_m[0] + (np.arange(c0, c1) + 0.5) * res - cx
        y = origin_xy_m[1] + (np.arange(r0, r1) + 0.5) * res - cy
        lx = c * x[None, :] + s * y[:, None]
        ly = -s * x[None, :] + c * y[:, None]
        tol = 0.5 * res * (abs(c) + abs(s))
        occ[r0:r1, c0:c1] |= (np.abs(lx) <= hx + tol) & (np.abs(ly) <= hy + tol)
    return occ


def world_map(
    model, resolution_m: float, z_low_m: float, z_high_m: float, source: str = "world"
) -> StaticMap:
    """The true map of the world of a compiled ``model``: its obstacles in the robot's height
    range."""
    boxes = obstacle_boxes(model, z_low_m, z_high_m)
    if not len(boxes.names):
        raise ValueError(f"{source}: no obstacle in the robot's height range to make a map of")
    ext = (
        np.abs(np.cos(boxes.yaw_rad))[:, None] * boxes.half_xy_m
        + np.abs(np.sin(boxes.yaw_rad))[:, None] * boxes.half_xy_m[:, ::-1]
    )
    lo = (boxes.centre_xy_m - ext).min(0) - MARGIN_M
    hi = (boxes.centre_xy_m + ext).max(0) + MARGIN_M
    origin = (
        float(np.floor(lo[0] / resolution_m) * resolution_m),
        float(np.floor(lo[1] / resolution_m) * resolution_m),
    )
    shape = (
        int(math.ceil((hi[1] - origin[1]) / resolution_m)),
        int(math.ceil((hi[0] - origin[0]) / resolution_m)),
    )
    occ = rasterise(boxes, resolution_m, origin, shape)
    return StaticMap(occ, np.zeros(shape, bool), float(resolution_m), origin, source)


def yaml_map(path: str | Path) -> StaticMap:
    """A map_server map (YAML + PGM) as map_server reads it; raises MapError (one line) if it cannot
    be."""
    from amr_twin.model.occupancy_map import load_map
    from amr_twin.model.worlds import MapError

    grid = load_map(path)
    if abs(grid.origin_xyyaw[2]) > 1e-9:
        raise MapError(
            f"{path}: origin yaw {grid.origin_xyyaw[2]} must be 0 for navigation (as nav2's "
            f"costmap)"
        )
    occ = grid.occupied[::-1].copy()
    unknown = ~(occ | grid.free[::-1])
    return StaticMap(
        occ, unknown, grid.resolution_m, (grid.origin_xyyaw[0], grid.origin_xyyaw[1]), str(path)
    )
