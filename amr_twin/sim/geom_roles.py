"""The roles of a world's geoms for one robot (its own, its support, floors, actors, other robots)
and which contacts of the last step are collisions (:mod:`amr_twin.sim.collisions`).

Part of the physics layer (``PHYSICS_LAYER``): reads MjData's contacts."""

from __future__ import annotations

import math

import mujoco
import numpy as np

from amr_twin.sim.robot_bodies import robot_name, robot_roots

PHYSICS_LAYER = True

SUPPORT_TILT_DEG = 30.0
"""A wheel or caster contact whose normal is within this angle of vertical is standing, deg."""

_FLOOR_TYPES = (mujoco.mjtGeom.mjGEOM_PLANE, mujoco.mjtGeom.mjGEOM_HFIELD)
IGNORE, COLLIDE, BY_NORMAL = 0, 1, 2
"""What a contact pair is (:meth:`GeomRoles.kind`): not a collision, one, or one unless its normal
is within :data:`SUPPORT_TILT_DEG` of vertical."""


def _name(m: mujoco.MjModel, kind: mujoco.mjtObj, i: int, fallback: str) -> str:
    return mujoco.mj_id2name(m, kind, i) or fallback


class GeomRoles:
    """Which geoms are the robot's, which support it, which are floors; names for reports."""

    def __init__(self, physics):
        m = self.model = physics.model
        self.prefix = physics.prefix
        root = m.body_rootid[physics.base_body]
        roots = m.body_rootid[m.geom_bodyid]
        self.robot = roots == root  # (ngeom,) bool
        self.support = np.zeros(m.ngeom, bool)
        self.support[list(physics.support.geoms.values())] = True
        self.floor = np.isin(m.geom_type, _FLOOR_TYPES) & ~self.robot
        self.other_robot = robot_roots(m)[roots] & ~self.robot  # (ngeom,) bool: another robot's
        self.actor = (
            (m.body_mocapid[m.geom_bodyid] >= 0) | self.other_robot
        ) & ~self.robot  # (ngeom,) bool: a person's, a jack's, another robot's
        self._pair: dict[tuple[int, int], int] = {}
        self._part: dict[int, str] = {}
        self._world: dict[int, str] = {}

    def kind(self, g1: int, g2: int) -> int:
        """IGNORE, COLLIDE or BY_NORMAL (a support geom on a non-floor world geom)."""
        key = (g1, g2)
        k = self._pair.get(key)
        if k is None:
            r1, r2 = bool(self.robot[g1]), bool(self.robot[g2])
            if r1 == r2:
                k = IGNORE  # world-world, or the robot with itself
            else:
                part, other = (g1, g2) if r1 else (g2, g1)
                if self.support[part] and not self.actor[other]:
                    k = IGNORE if self.floor[other] else BY_NORMAL
                else:
                    k = COLLIDE
            self._pair[key] = k
        return k

    def robot_part(self, g: int) -> str:
        """The robot body of geom ``g``, without the robot's prefix (``base_link``,
        ``wheel_left_link``)."""
        part = self._part.get(g)
        if part is None:
            m = self.model
            body = int(m.geom_bodyid[g])
            part = self._part[g] = _name(
                m, mujoco.mjtObj.mjOBJ_BODY, body, f"body {body}"
            ).removeprefix(self.prefix)
        return part

    def world_name(self, g: int) -> str:
        """The world geom's name, or ``geom <id>`` (in body ``<name>``) when unnamed; an actor's
        body name; another robot's name."""
        name = self._world.get(g)
        if name is None:
            name = self._world[g] = self._world_name(g)
        return name

    def _world_name(self, g: int) -> str:
        m = self.model
        body = m.geom_bodyid[g]
        if self.other_robot[g]:
            return robot_name(m, m.body_rootid[body])
        if self.actor[g]:
            return _name(m, mujoco.mjtObj.mjOBJ_BODY, body, f"body {body}")
        name = mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_GEOM, g)
        if name:
            return name
        return f"geom {g}" + (
            f" of body {_name(m, mujoco.mjtObj.mjOBJ_BODY, body, str(body))}" if body else ""
        )


_COS_SUPPORT = math.cos(math.radians(SUPPORT_TILT_DEG))


def collision_contacts(roles: GeomRoles, data: mujoco.MjData, pairs: list | None = None):
    """Contacts of the last step that are collisions.

    Returns ``(hits, by_normal)``: ``hits`` lists ``(contact index, robot geom, world
    geom)``; ``by_normal`` is True when a wheel or caster stands on a world geom other
    than a floor (its verdict depends on the contact normal, so it may change while
    the pairs stay the same).
    """
    out, by_normal = [], False
    if data.ncon == 0:
        return out, by_normal
    if pairs is None:
        pairs = data.contact.geom.tolist()
    for i, (g1, g2) in enumerate(pairs):
        k = roles.kind(g1, g2)
        if k == IGNORE:
            continue
        if k == BY_NORMAL:
            by_normal = True
            if abs(float(data.contact.frame[i][2])) >= _COS_SUPPORT:
                continue
        robot_g, world_g = (g1, g2) if roles.robot[g1] else (g2, g1)
        out.append((i, robot_g, world_g))
    return out, by_normal
