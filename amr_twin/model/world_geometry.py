"""The world as a 2D scanner sees it: box footprints cut by a horizontal plane.

Used to judge a map against the world it was built in (the map's walls against the
world's walls) and a route's clearance. Boxes come from a compiled model (geom
group 0, after ``mj_forward``), so default classes and rotations are resolved by
MuJoCo; a box is kept when it spans the plane's height ``z_m`` (an actor's, a mocap body that moves,
never: amr_twin/model/actors.py). Distances are
computed in numpy for many points at once.

Part of the physics layer (``PHYSICS_LAYER``): forwards a private MjData of a freshly compiled world
to read its static box geoms; no twin's state is read or written.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

PHYSICS_LAYER = True

WORLD_GROUP = 0


@dataclass(frozen=True)
class Footprints:
    """Oriented rectangles in the plane: centres (K, 2) m, half sizes (K, 2) m, yaw (K,) rad,
    names."""

    centre_xy_m: np.ndarray
    half_xy_m: np.ndarray
    yaw_rad: np.ndarray
    names: tuple[str, ...]

    def __len__(self) -> int:
        return len(self.names)

    def __getitem__(self, index: slice) -> "Footprints":
        """The footprints of a slice (e.g. ``boxes[k:k + 1]``: one of them)."""
        return Footprints(
            self.centre_xy_m[index], self.half_xy_m[index], self.yaw_rad[index], self.names[index]
        )


def scan_plane_boxes(model, z_m: float) -> Footprints:
    """Footprints of the world's box geoms (group 0) of a compiled ``model`` that span height
    ``z_m``.

    The geometry is forwarded in a private ``MjData`` (world geoms do not move).
    """
    import mujoco

    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    keep = []
    for g in range(model.ngeom):
        if (
            model.geom_group[g] != WORLD_GROUP
            or model.geom_type[g] != mujoco.mjtGeom.mjGEOM_BOX
            or model.body_mocapid[model.geom_bodyid[g]] >= 0
        ):
            continue
        R = data.geom_xmat[g].reshape(3, 3)
        half_z = (
            np.abs(R[2]) @ model.geom_size[g]
        )  # vertical half extent of the (possibly rotated) box
        if abs(data.geom_xpos[g][2] - z_m) <= half_z:
            keep.append(g)
    centre = np.array([data.geom_xpos[g][:2] for g in keep]).reshape(-1, 2)
    half = np.array([model.geom_size[g][:2] for g in keep]).reshape(-1, 2)
    yaw = np.array([np.arctan2(data.geom_xmat[g][3], data.geom_xmat[g][0]) for g in keep])
    names = tuple(mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_GEOM, g) or f"geom{g}" for g in keep)
    return Footprints(centre, half, yaw, names)


def distance_to_boxes_m(xy_m: np.ndarray, boxes: Footprints) -> np.ndarray:
    """Distance (N,) m from each point ``xy_m`` (N, 2) to the nearest footprint (0 inside one)."""
    xy = np.asarray(xy_m, float).reshape(-1, 2)
    if len(boxes) == 0:
        return np.full(len(xy), np.inf)
    d = xy[:, None, :] - boxes.centre_xy_m[None]  # (N, K, 2)
    c, s = np.cos(boxes.yaw_rad), np.sin(boxes.yaw_rad)
    local = np.stack([c * d[..., 0] + s * d[..., 1], -s * d[..., 0] + c * d[..., 1]], axis=-1)
    out = np.maximum(np.abs(local) - boxes.half_xy_m[None], 0.0)
    return np.sqrt((out**2).sum(-1)).min(axis=1)


def surface_samples_m(boxes: Footprints, spacing_m: float) -> np.ndarray:
    """Points (M, 2) every ``spacing_m`` along the outlines of the footprints."""
    pts = []
    for (cx, cy), (hx, hy), yaw in zip(boxes.centre_xy_m, boxes.half_xy_m, boxes.yaw_rad):
        corners = np.array([[-hx, -hy], [hx, -hy], [hx, hy], [-hx, hy], [-hx, -hy]])
        for a, b in zip(corners[:-1], corners[1:]):
            n = max(2, int(np.ceil(np.linalg.norm(b - a) / spacing_m)) + 1)
            seg = a + np.linspace(0.0, 1.0, n)[:, None] * (b - a)
            c, s = np.cos(yaw), np.sin(yaw)
            pts.append(
                np.column_stack(
                    [cx + c * seg[:, 0] - s * seg[:, 1], cy + s * seg[:, 0] + c * seg[:, 1]]
                )
            )
    return np.vstack(pts) if pts else np.zeros((0, 2))
