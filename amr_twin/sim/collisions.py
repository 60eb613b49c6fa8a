"""Contacts of the robot with the world: detected, reported, and checked before a run.

A *collision* is any contact between a geom of the robot and a geom of the world
other than a wheel or a caster ball standing on the floor (a plane or height
field, or an upward-facing surface: contact normal within
:data:`~amr_twin.sim.geom_roles.SUPPORT_TILT_DEG`
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
from dataclasses import dataclass, field
from pathlib import Path

import mujoco
import numpy as np

from amr_twin.sim.geom_roles import GeomRoles, collision_contacts
from amr_twin.sim.grid_steps import CHANGED, sampler
from amr_twin.base.c_layout import register
from amr_twin.base.native_build import open_helper

PHYSICS_LAYER = True

MERGE_GAP_S = 0.1
"""Contact with the same world geom lost for less than this continues the episode, s."""

FORCE_EVERY_S = 0.1
"""While the same contacts persist, their normal forces are read this often (peak force), s."""

FORCE_EVERY_US = int(FORCE_EVERY_S * 1_000_000)
C_SOURCE = Path(__file__).with_name("collisions.c")
MEMO_PAIRS = 256
"""Contact pairs the C helper keeps; with more in contact every instant is classified in Python."""


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
