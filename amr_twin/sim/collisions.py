"""Contacts of the robot with the world: detected, reported, and checked before a run.

A *collision* is any contact between a geom of the robot and a geom of the world
other than a wheel or a caster ball standing on the floor (a plane or height
field, or an upward-facing surface: contact normal within :data:`SUPPORT_TILT_DEG`
of vertical). The chassis touching a rack, a wheel rubbing a wall and the robot
lying on the floor after tipping over are collisions. Any contact with an actor (a
person or pallet jack, :mod:`amr_twin.model.actors`: a mocap body) is one, a wheel on a
jack's fork too; it is named by the actor's body (``person_0``), all its geoms one episode. In a
world of several robots each robot has its own monitor, and any contact with another robot is a
collision named by that robot (``amr-2``), the monitor's own robot in :attr:`Collision.robot`.

Reasons and measurements: docs/explanation/actors.md#amr_twinsimcollisions.

Part of the physics layer (``PHYSICS_LAYER``): a grid sampler: reads MjData's contacts and their
forces (``mj_contactForce``) at each grid instant."""

from __future__ import annotations

import ctypes
import functools
import math
from dataclasses import dataclass, field
from pathlib import Path

import mujoco
import numpy as np

from amr_twin.sim.grid_steps import CHANGED, sampler
from amr_twin.sim.robot_bodies import robot_name, robot_roots
from amr_twin.base.c_layout import register
from amr_twin.base.native_build import open_helper

PHYSICS_LAYER = True

SUPPORT_TILT_DEG = 30.0
"""A wheel or caster contact whose normal is within this angle of vertical is standing, deg."""

MERGE_GAP_S = 0.1
"""Contact with the same world geom lost for less than this continues the episode, s."""

FORCE_EVERY_S = 0.1
"""While the same contacts persist, their normal forces are read this often (peak force), s."""

_FLOOR_TYPES = (mujoco.mjtGeom.mjGEOM_PLANE, mujoco.mjtGeom.mjGEOM_HFIELD)
FORCE_EVERY_US = int(FORCE_EVERY_S * 1_000_000)
C_SOURCE = Path(__file__).with_name("collisions.c")
MEMO_PAIRS = 256
"""Contact pairs the C helper keeps; with more in contact every instant is classified in Python."""
_IGNORE, _COLLIDE, _BY_NORMAL = 0, 1, 2


@dataclass
class Collision:
    """One contact episode between the robot and a world geom.

    ``t_s``/``x_m``/``y_m``/``z_m``: time and world position of the first contact
    point; ``until_s``: last instant it was seen; ``hit``: the world geom's name (an actor's body
    name, another robot's name); ``robot_parts``: the robot bodies that touched it;
    ``robot_pose``: base pose (x_m, y_m, yaw_rad) at the first contact; ``peak_force_n``: largest
    normal contact force seen, N; ``robot``: whose collision it is, a fleet robot's name (empty
    for the lone robot).
    """

    t_s: float
    x_m: float
    y_m: float
    z_m: float
    hit: str
    robot_parts: list[str]
    robot_pose: tuple[float, float, float]
    until_s: float = 0.0
    peak_force_n: float = 0.0
    robot: str = ""
    _last_us: int = field(default=0, repr=False)

    def as_dict(self) -> dict:
        """JSON-ready form (times s, positions m, force N; ``robot`` for a fleet robot's)."""
        x, y, yaw = self.robot_pose
        return {
            **({"robot": self.robot} if self.robot else {}),
            "t_s": round(self.t_s, 4),
            "until_s": round(self.until_s, 4),
            "hit": self.hit,
            "robot_parts": list(self.robot_parts),
            "x_m": round(self.x_m, 4),
            "y_m": round(self.y_m, 4),
            "z_m": round(self.z_m, 4),
            "robot_pose": {"x_m": round(x, 4), "y_m": round(y, 4), "yaw_rad": round(yaw, 4)},
            "peak_force_n": round(self.peak_force_n, 2),
        }


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
        """_IGNORE, _COLLIDE or _BY_NORMAL (a support geom on a non-floor world geom)."""
        key = (g1, g2)
        k = self._pair.get(key)
        if k is None:
            r1, r2 = bool(self.robot[g1]), bool(self.robot[g2])
            if r1 == r2:
                k = _IGNORE  # world-world, or the robot with itself
            else:
                part, other = (g1, g2) if r1 else (g2, g1)
                if self.support[part] and not self.actor[other]:
                    k = _IGNORE if self.floor[other] else _BY_NORMAL
                else:
                    k = _COLLIDE
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
        if k == _IGNORE:
            continue
        if k == _BY_NORMAL:
            by_normal = True
            if abs(float(data.contact.frame[i][2])) >= _COS_SUPPORT:
                continue
        robot_g, world_g = (g1, g2) if roles.robot[g1] else (g2, g1)
        out.append((i, robot_g, world_g))
    return out, by_normal


class _Memo(ctypes.Structure):
    """``contact_memo`` of collisions.c."""

    _fields_ = [
        ("valid", ctypes.c_int),
        ("n", ctypes.c_int),
        ("cap", ctypes.c_int),
        ("pairs", ctypes.POINTER(ctypes.c_int)),
    ]


register(C_SOURCE, contact_memo=_Memo)


class CollisionMonitor:
    """Grid sampler that records the robot's collisions (see the module notes).

    Parameters
    ----------
    physics : amr_twin.sim.physics.Physics
    stop : bool
        Ask the loop to stop at the first collision (the sampler returns True).
    native : bool
        Compare the pairs in C when the helper builds (:attr:`engine` says which runs).
    listeners : list, optional
        Callables ``f(collision)`` to tell of each new episode (a live list: the twin's
        ``on_collision`` hook's).
    """

    def __init__(
        self, physics, stop: bool = False, native: bool = True, listeners: list | None = None
    ):
        self.physics, self.stop = physics, stop
        self._data = physics.data
        self.roles = GeomRoles(physics)
        self._robot = "" if not self.roles.other_robot.any() else physics.prefix.rstrip("/")
        self.collisions: list[Collision] = []
        self.listeners: list = [] if listeners is None else listeners
        """Callables ``f(collision)`` told of each new episode as it begins (the twin's
        ``on_collision`` hook)."""
        self._open: dict[
            str, Collision
        ] = {}  # what was hit (a world geom's name, an actor's) -> its episode
        self._last_pairs: list | None = None
        self._last_full_us = -(1 << 62)
        self._force = np.zeros(6)
        self._memo = None
        lib, self.engine = open_helper(C_SOURCE, native)
        """Which compares the pairs: ``"C"`` or ``"Python (<why>)"``."""
        if lib is not None:
            self._use_native(lib)

    def _use_native(self, lib) -> None:
        self._pairs = (ctypes.c_int * (2 * MEMO_PAIRS))()
        memo = self._memo = _Memo(cap=MEMO_PAIRS, pairs=self._pairs)
        fn = lib.contacts_changed
        fn.restype, fn.argtypes = (
            ctypes.c_int,
            [ctypes.c_void_p, ctypes.c_void_p],
        )  # self._data outlives it
        self._changed = functools.partial(
            fn,
            ctypes.c_void_p(self._data._address),
            ctypes.cast(ctypes.pointer(memo), ctypes.c_void_p),
        )
        self._native = sampler(CHANGED, fn, self._data._address, memo)

    @property
    def grid_native(self):
        """The C form for the loop's grid in C (:mod:`amr_twin.sim.grid_steps`): the comparison
        of the pairs, the instant handed to :meth:`grid_resume` when they changed; None (the
        Python loop) without the helper or while a collision is open (each instant extends it)."""
        return self._native if self._memo is not None and not self._open else None

    def grid_resume(self, t_us: int) -> bool:
        """Grid instant ``t_us`` whose pairs the C form found changed (and kept): classify them."""
        return self._classify(t_us, None)

    def __call__(self, t_us: int) -> bool:
        """Grid instant ``t_us``: physics is there. True asks the loop to stop."""
        d, memo = self._data, self._memo
        if memo is not None:
            same, pairs = not self._changed(), None
        else:
            pairs = d.contact.geom.tolist() if d.ncon else []
            same = pairs == self._last_pairs
        if same:  # the same contacts as at the last instant, verdict unchanged
            if not self._open:
                return False
            if t_us - self._last_full_us < FORCE_EVERY_US:  # an ongoing collision: extend it
                for ep in self._open.values():
                    ep._last_us, ep.until_s = t_us, t_us * 1e-6
                return self.stop
        return self._classify(t_us, pairs)

    def _classify(self, t_us: int, pairs: list | None) -> bool:
        d, memo = self._data, self._memo
        if pairs is None:
            pairs = d.contact.geom.tolist() if d.ncon else []
        hits, by_normal = collision_contacts(self.roles, d, pairs)
        for i, robot_g, world_g in hits:
            self._touch(t_us, i, robot_g, world_g)
        self._close_stale(t_us)
        self._last_full_us = t_us
        # cache only a verdict that cannot change while the pairs stay the same
        self._last_pairs = pairs if not by_normal else None
        if memo is not None:
            memo.valid = int(not by_normal and memo.n >= 0)
        return bool(hits) and self.stop

    def _touch(self, t_us: int, i: int, robot_g: int, world_g: int) -> None:
        m, d = self.physics.model, self.physics.data
        mujoco.mj_contactForce(m, d, i, self._force)
        force = abs(float(self._force[0]))
        part = self.roles.robot_part(robot_g)
        hit = self.roles.world_name(world_g)
        ep = self._open.get(hit)
        if ep is None:
            pos = d.contact.pos[i]
            pose = self.physics.pose()
            ep = Collision(
                t_us * 1e-6,
                float(pos[0]),
                float(pos[1]),
                float(pos[2]),
                hit,
                [part],
                (pose.x_m, pose.y_m, pose.yaw_rad),
                until_s=t_us * 1e-6,
                robot=self._robot,
            )
            self._open[hit] = ep
            self.collisions.append(ep)
            for listener in self.listeners:
                listener(ep)
        elif part not in ep.robot_parts:
            ep.robot_parts.append(part)
        ep._last_us = t_us
        ep.until_s = t_us * 1e-6
        ep.peak_force_n = max(ep.peak_force_n, force)

    def _close_stale(self, t_us: int) -> None:
        gap_us = int(MERGE_GAP_S * 1e6)
        for g in [g for g, ep in self._open.items() if t_us - ep._last_us > gap_us]:
            del self._open[g]

    def as_dicts(self) -> list[dict]:
        return [c.as_dict() for c in self.collisions]
