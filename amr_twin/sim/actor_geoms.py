"""The actors' and the robot's colliding geoms, and the gap between them at an actor's next pose.

What :mod:`amr_twin.sim.actors` needs to stop an actor where it touches the robot
(docs/explanation/actors.md): each actor's colliding geoms with their frames in the actor's (to
place them at a pose it has not reached), the robot's, the reach of each set in the floor's plane
(to skip the distances when far), and
:func:`gap_after`, the Python twin of ``gap_after`` of ``actors.c`` (the same operations, so the
same bits).

Part of the physics layer (``PHYSICS_LAYER``): reads MjData's geom poses and writes an actor's
geoms' (its caller puts them back), calls ``mj_geomDistance``.
"""

from __future__ import annotations

import math

import numpy as np

PHYSICS_LAYER = True
CUTOFF_M = 0.01
"""Distances beyond this are not needed (``mj_geomDistance``'s distmax), m."""


def _radius_m(m, g: int) -> float:
    """How far geom ``g`` reaches from its centre in any horizontal direction, at most, m."""
    import mujoco

    size, t = m.geom_size[g], m.geom_type[g]
    if t == mujoco.mjtGeom.mjGEOM_BOX:
        return float(math.sqrt(size[0] ** 2 + size[1] ** 2 + size[2] ** 2))
    return float(max(size[0], size[1]) if t == mujoco.mjtGeom.mjGEOM_ELLIPSOID else size[0])


def actor_geoms(physics, body: str) -> tuple[np.ndarray, np.ndarray, float]:
    """The colliding geoms (int32) of the actor ``body``, each one's position and rotation matrix in
    its frame (n, 12), and their reach from its origin in the floor's plane, m."""
    import mujoco

    m = physics.model
    b = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, body)
    geoms = [
        g
        for g in range(m.ngeom)
        if m.geom_bodyid[g] == b and (m.geom_contype[g] or m.geom_conaffinity[g])
    ]
    local = np.zeros((len(geoms), 12))
    for row, g in zip(local, geoms):
        row[:3] = m.geom_pos[g]
        mujoco.mju_quat2Mat(row[3:], m.geom_quat[g])
    reach = max((math.hypot(*m.geom_pos[g][:2]) + _radius_m(m, g) for g in geoms), default=0.0)
    return np.asarray(geoms, np.int32), local, reach


def robot_geoms(physics) -> tuple[list[int], float]:
    """The robot's colliding geoms and their farthest point from the base's origin in the floor's
    plane, m, with 0.05 m for the wheels' turning and the casters' swivel."""
    m, d = physics.model, physics.data
    root = m.body_rootid[physics.base_body]
    geoms = [
        g
        for g in range(m.ngeom)
        if m.body_rootid[m.geom_bodyid[g]] == root and (m.geom_contype[g] or m.geom_conaffinity[g])
    ]
    base = d.xpos[physics.base_body]
    reach = max(
        (math.hypot(*(d.geom_xpos[g][:2] - base[:2])) + _radius_m(m, g) for g in geoms), default=0.0
    )
    return geoms, reach + 0.05


def gap_after(physics, robot: np.ndarray, geoms: list, local: list, pose) -> float:
    """The least signed distance (up to :data:`CUTOFF_M`) from an actor's ``geoms`` (their frames
    ``local``, rows of 12) placed with the actor at ``pose`` (x_m, y_m, yaw_rad) to the ``robot``'s
    geoms, m; the actor's geoms are left there in MjData."""
    import mujoco

    x, y, yaw = pose
    cs, sn = math.cos(yaw), math.sin(yaw)
    m, d = physics.model, physics.data
    for g, p in zip(geoms, local):
        d.geom_xpos[g] = (x + (cs * p[0] - sn * p[1]), y + (sn * p[0] + cs * p[1]), p[2])
        d.geom_xmat[g] = (
            [cs * p[3 + j] - sn * p[6 + j] for j in range(3)]
            + [sn * p[3 + j] + cs * p[6 + j] for j in range(3)]
            + [p[9 + j] for j in range(3)]
        )
    gap = CUTOFF_M
    for g in geoms:
        for k in robot.tolist():
            dist = mujoco.mj_geomDistance(m, d, g, k, CUTOFF_M, None)
            if dist < gap:
                gap = dist
    return gap
