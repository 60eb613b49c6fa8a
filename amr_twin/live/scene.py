"""The twin's world and robot as a Foxglove ``SceneUpdate``, for ``/twin/scene``.

Reasons and measurements: docs/how-to/live.md#amr_twinlivescene."""

from __future__ import annotations

import math

import mujoco
import numpy as np

from amr_twin.ros.ros_state import ROBOT
from amr_twin.analysis.se2 import yaw_of_quaternion

VISUAL_GROUPS = (
    0,
    1,
    4,
)  # world, robot visuals, payload (as in the .rrd: rerun_world.VISUAL_GROUPS)
GHOST_RGBA = (0.2, 0.75, 0.25, 0.35)
COLLISION_RGBA = (0.9, 0.1, 0.1, 0.9)
FLOOR_HALF_M = 15.0
"""Half size drawn for an infinite plane (MuJoCo size 0), m."""


def _rgba(m: mujoco.MjModel, g: int) -> tuple[float, ...]:
    mat = m.geom_matid[g]
    rgba = m.mat_rgba[mat] if mat >= 0 else m.geom_rgba[g]
    return tuple(float(v) for v in np.clip(rgba, 0.0, 1.0))


def _mat_quat(xmat: np.ndarray) -> np.ndarray:
    q = np.empty(4)
    mujoco.mju_mat2Quat(q, np.asarray(xmat, float).ravel())
    return q


def _qmul(a, b) -> np.ndarray:
    q = np.empty(4)
    mujoco.mju_mulQuat(q, np.asarray(a, float), np.asarray(b, float))
    return q


def _compose(p_a, q_a, p_b, q_b) -> tuple[np.ndarray, np.ndarray]:
    """Pose ``a * b`` (positions (3,), quaternions w, x, y, z)."""
    v = np.empty(3)
    mujoco.mju_rotVecQuat(v, np.asarray(p_b, float), np.asarray(q_a, float))
    return np.asarray(p_a, float) + v, _qmul(q_a, q_b)


def _inverse(p, q) -> tuple[np.ndarray, np.ndarray]:
    qi = np.array([q[0], -q[1], -q[2], -q[3]], float)
    v = np.empty(3)
    mujoco.mju_rotVecQuat(v, -np.asarray(p, float), qi)
    return v, qi


def planar_origin(pos, quat) -> tuple[np.ndarray, np.ndarray]:
    """The odom frame's pose in the world for a base pose: its position and yaw only (odom is
    planar)."""
    w, x, y, z = quat
    yaw = yaw_of_quaternion(w, x, y, z)
    return np.asarray(pos, float).copy(), np.array([math.cos(yaw / 2), 0.0, 0.0, math.sin(yaw / 2)])


class SceneBuilder:
    """Builds the ``/twin/scene`` entities of one twin (model and start state read once).

    Parameters
    ----------
    model : mujoco.MjModel
        The compiled twin (``twin.observables.model``).
    named : amr_twin.sim.named_index.NamedIndex
        Its named views at t = 0, after settling (``twin.observables.named``): the world's geoms and
        the start pose are read from them.
    """

    def __init__(self, model: mujoco.MjModel, named):
        import foxglove.messages as fm

        self.fm = fm
        d = named.data
        base = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, ROBOT + "base_link")
        self._odom_in_world = planar_origin(d.xpos[base], d.xquat[base])
        world_from_odom_inv = _inverse(*self._odom_in_world)
        base_inv = _inverse(d.xpos[base], d.xquat[base])
        self._world: list[tuple] = []  # (kind, pos, quat, size, rgba) in odom
        self._links: dict[str, list[tuple]] = {}  # link -> geoms in the link's frame
        self._ghost: list[tuple] = []  # robot geoms in base_link's frame (the start configuration)
        self._actors: list[list[tuple]] = [
            [] for _ in range(model.nmocap)
        ]  # per mocap body: geoms in its frame
        for g in range(model.ngeom):
            if model.geom_group[g] not in VISUAL_GROUPS or model.geom_rgba[g][3] == 0:
                continue
            shape = self._shape(model, g)
            if shape is None:
                continue
            kind, size = shape
            rgba = _rgba(model, g)
            body = int(model.geom_bodyid[g])
            name = mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_BODY, body) or ""
            gpos, gquat = d.geom_xpos[g], _mat_quat(d.geom_xmat[g])
            if model.body_mocapid[body] >= 0:  # an actor: drawn where actors/poses puts it
                self._actors[model.body_mocapid[body]].append(
                    (kind, model.geom_pos[g].copy(), model.geom_quat[g].copy(), size, rgba)
                )
            elif name.startswith(ROBOT):
                self._links.setdefault(name[len(ROBOT) :], []).append(
                    (kind, model.geom_pos[g].copy(), model.geom_quat[g].copy(), size, rgba)
                )
                p, q = _compose(*base_inv, gpos, gquat)
                self._ghost.append((kind, p, q, size, GHOST_RGBA))
            else:
                p, q = _compose(*world_from_odom_inv, gpos, gquat)
                if kind == "plane":  # drawn as a thin box just below the surface
                    p = p - _rotate(q, [0.0, 0.0, 0.001])
                self._world.append(("box" if kind == "plane" else kind, p, q, size, rgba))

    @staticmethod
    def _shape(m: mujoco.MjModel, g: int):
        T, size = mujoco.mjtGeom, m.geom_size[g]
        typ = int(m.geom_type[g])
        if typ == T.mjGEOM_BOX:
            return "box", 2 * size[:3]
        if typ == T.mjGEOM_PLANE:
            half = [s if s > 0 else FLOOR_HALF_M for s in size[:2]]
            return "plane", np.array([2 * half[0], 2 * half[1], 0.002])
        if typ == T.mjGEOM_SPHERE:
            return "sphere", np.full(3, 2 * size[0])
        if typ == T.mjGEOM_ELLIPSOID:
            return "sphere", 2 * size[:3]
        if typ in (int(T.mjGEOM_CYLINDER), int(T.mjGEOM_CAPSULE)):
            return "cylinder", np.array([2 * size[0], 2 * size[0], 2 * size[1]])
        return None  # meshes, height fields: none in the twin's worlds

    # -- foxglove messages ----------------------------------------------------------
    def _pose(self, p, q):
        fm = self.fm
        return fm.Pose(
            position=fm.Vector3(x=float(p[0]), y=float(p[1]), z=float(p[2])),
            orientation=fm.Quaternion(x=float(q[1]), y=float(q[2]), z=float(q[3]), w=float(q[0])),
        )

    def _entity(
        self, entity_id: str, frame: str, geoms, t_ns: int, frame_locked: bool = False, offset=None
    ):
        fm = self.fm
        cubes, spheres, cylinders = [], [], []
        for kind, p, q, size, rgba in geoms:
            if offset is not None:
                p, q = _compose(*offset, p, q)
            pose = self._pose(p, q)
            sz = fm.Vector3(x=float(size[0]), y=float(size[1]), z=float(size[2]))
            color = fm.Color(r=rgba[0], g=rgba[1], b=rgba[2], a=rgba[3])
            if kind == "box":
                cubes.append(fm.CubePrimitive(pose=pose, size=sz, color=color))
            elif kind == "sphere":
                spheres.append(fm.SpherePrimitive(pose=pose, size=sz, color=color))
            else:
                cylinders.append(
                    fm.CylinderPrimitive(
                        pose=pose, size=sz, bottom_scale=1.0, top_scale=1.0, color=color
                    )
                )
        return fm.SceneEntity(
            timestamp=fm.Timestamp(t_ns // 1_000_000_000, t_ns % 1_000_000_000),
            frame_id=frame,
            id=entity_id,
            frame_locked=frame_locked,
            cubes=cubes,
            spheres=spheres,
            cylinders=cylinders,
        )

    def static_update(self, t_ns: int = 0):
        """The world (in ``odom``) and each robot link (in its own frame): sent once and to late
        subscribers."""
        entities = [self._entity("world", "odom", self._world, t_ns)]
        entities += [
            self._entity(f"robot/{link}", link, geoms, t_ns, frame_locked=True)
            for link, geoms in sorted(self._links.items())
        ]
        return self.fm.SceneUpdate(entities=entities)

    def ghost_update(self, t_ns: int, pos, quat):
        """The robot at its true world pose ``pos`` (3,), ``quat`` (4,) w, x, y, z, drawn in
        ``odom``."""
        odom_inv = _inverse(*self._odom_in_world)
        offset = _compose(*odom_inv, pos, quat)
        return self.fm.SceneUpdate(
            entities=[self._entity("ground_truth", "odom", self._ghost, t_ns, offset=offset)]
        )

    def actors_update(self, t_ns: int, poses_world):
        """The actors at their world poses ``poses_world`` ((x_m, y_m, yaw_rad) each, in the order
        of ``actors/poses``), drawn in ``odom``."""
        odom_inv = _inverse(*self._odom_in_world)
        geoms = []
        for (x, y, yaw), parts in zip(poses_world, self._actors):
            pose = _compose(
                *odom_inv, [x, y, 0.0], [math.cos(yaw / 2), 0.0, 0.0, math.sin(yaw / 2)]
            )
            geoms += [
                (kind, *_compose(*pose, p, q), size, rgba) for kind, p, q, size, rgba in parts
            ]
        return self.fm.SceneUpdate(entities=[self._entity("actors", "odom", geoms, t_ns)])

    def collisions_update(self, t_ns: int, points_world):
        """Red spheres (0.1 m) at the collisions' first contacts (world points (n, 3), m), in
        ``odom``."""
        odom_inv = _inverse(*self._odom_in_world)
        unit = np.array([1.0, 0.0, 0.0, 0.0])
        geoms = [
            ("sphere", _compose(*odom_inv, p, unit)[0], unit, np.full(3, 0.1), COLLISION_RGBA)
            for p in np.asarray(points_world, float).reshape(-1, 3)
        ]
        return self.fm.SceneUpdate(entities=[self._entity("collisions", "odom", geoms, t_ns)])


def _rotate(q, v) -> np.ndarray:
    out = np.empty(3)
    mujoco.mju_rotVecQuat(out, np.asarray(v, float), np.asarray(q, float))
    return out
