"""The actors in the running twin: moved on the loop's grid, their true poses on ``actors/poses``.

Reasons and measurements: docs/explanation/actors.md#amr_twinsimactors.

Part of the physics layer (``PHYSICS_LAYER``): a grid sampler in C: moves the actors' mocap bodies
in MjData."""

from __future__ import annotations

import ctypes
import math
from collections import deque
from pathlib import Path

import numpy as np

from amr_twin.model.actor_paths import actor_path
from amr_twin.model.actors import Actor, body_name
from amr_twin.sim.actor_geoms import actor_geoms, gap_after, robot_geoms
from amr_twin.sim.grid_rows import GridRows
from amr_twin.sim.grid_steps import TIMED, sampler
from amr_twin.base.c_layout import register
from amr_twin.base.native_build import address, mujoco_address, open_helper

PHYSICS_LAYER = True

C_SOURCE = Path(__file__).with_name("actors.c")
ACTOR_GEOMS, BISECTIONS = 8, 12
"""An actor's colliding geoms checked against the robot at most (more: never held); bisections of a
step."""
PUBLISH_PERIOD_US = 100_000
"""``actors/poses`` every 100 ms (10 Hz)."""
TOPIC, FRAME = "actors/poses", "map"
US = 1_000_000


class _State(ctypes.Structure):
    """``actor_state`` of actors.c."""

    _fields_ = [
        ("phases", ctypes.c_void_p),
        ("nphase", ctypes.c_int),
        ("mocap", ctypes.c_int),
        ("period_s", ctypes.c_double),
        ("start_us", ctypes.c_int64),
        ("progress_us", ctypes.c_int64),
        ("last_us", ctypes.c_int64),
        ("stop_m", ctypes.c_double),
        ("pose", ctypes.c_double * 3),
        ("geoms", ctypes.c_void_p),
        ("local", ctypes.c_void_p),
        ("ngeom", ctypes.c_int),
        ("reach_m", ctypes.c_double),
        ("give_way_us", ctypes.c_int64),
        ("waited_us", ctypes.c_int64),
        ("held_us", ctypes.c_int64),
        ("touch_m", ctypes.c_double),
        ("touching", ctypes.c_int),
    ]


class _Ctx(ctypes.Structure):
    """``actors_ctx`` of actors.c."""

    _fields_ = [
        ("n", ctypes.c_int),
        ("a", ctypes.POINTER(_State)),
        ("base_body", ctypes.c_int),
        ("half_len_m", ctypes.c_double),
        ("half_wid_m", ctypes.c_double),
        ("m", ctypes.c_void_p),
        ("distance", ctypes.c_void_p),
        ("robot_geoms", ctypes.c_void_p),
        ("nrobot", ctypes.c_int),
        ("robot_reach_m", ctypes.c_double),
    ]


register(C_SOURCE, actor_state=_State, actors_ctx=_Ctx)


class ActorMotion:
    """Moves the ``actors`` (:class:`~amr_twin.model.actors.Actor`, in the order their bodies were
    built) of a twin's ``physics`` on the loop's grid (module notes).

    :attr:`update` is the grid sampler (``update(t_us)``): the C helper when built, else
    :meth:`update_python`; ``native=False`` forces the Python twin (:attr:`engine` says which).
    """

    def __init__(self, physics, actors: tuple[Actor, ...], cfg, native: bool = True):
        self.physics, self.actors = physics, tuple(actors)
        self.names = tuple(body_name(i, a) for i, a in enumerate(self.actors))
        """Each actor's body name (``person_0``, ...), as collisions report it."""
        self.paths = [actor_path(a, cfg) for a in self.actors]
        self._phases = [np.ascontiguousarray(p.phases, np.float64) for p in self.paths]
        n = len(self.actors)
        self._states = (_State * max(n, 1))()
        robot, self._robot_reach_m = robot_geoms(physics)
        self._geoms = [actor_geoms(physics, name) for name in self.names]
        self._robot = np.asarray(robot, np.int32)
        for s, a, path, phases, name, (geoms, local, reach) in zip(
            self._states, self.actors, self.paths, self._phases, self.names, self._geoms
        ):
            s.phases, s.nphase, s.mocap = address(phases), len(phases), physics.mocap_index(name)
            s.period_s, s.start_us = path.period_s, int(round(a.start_s * US))
            s.progress_us, s.last_us, s.stop_m = 0, 0, a.stop_within_m
            s.pose[0], s.pose[1], s.pose[2] = path.pose_at(0.0)
            s.geoms, s.local, s.ngeom, s.reach_m = address(geoms), address(local), len(geoms), reach
            kind = getattr(cfg.actors, a.kind)
            s.give_way_us, s.touch_m = int(round(kind.give_way_s * US)), kind.touch_m
            s.waited_us = s.held_us = s.touching = 0
        self._ctx = _Ctx(
            n=n,
            a=ctypes.cast(self._states, ctypes.POINTER(_State)),
            base_body=physics.base_body,
            half_len_m=cfg.chassis.length_m / 2,
            half_wid_m=cfg.half_width_m,
            m=physics.model._address,
            distance=mujoco_address("mj_geomDistance"),
            robot_geoms=address(self._robot),
            nrobot=len(self._robot),
            robot_reach_m=self._robot_reach_m,
        )
        self._waits = any(a.stop_within_m > 0 for a in self.actors)
        self.update = self.update_python
        """The grid sampler: the C helper when built, else :meth:`update_python`."""
        lib, self.engine = open_helper(C_SOURCE, native)
        """Which runs: ``"C"`` or ``"Python (<why>)"``."""
        self._row_c = None
        if lib is not None:
            self._use_native(lib)

    def _use_native(self, lib) -> None:
        fn = lib.actors_update
        fn.restype, fn.argtypes = None, [ctypes.c_void_p, ctypes.c_void_p, ctypes.c_int64]
        ctx, d = ctypes.addressof(self._ctx), self.physics.data._address
        self._keep = (self.physics.model, self.physics.data)  # the data outlives every call

        def update(t_us: int, _fn=fn, _ctx=ctx, _d=d) -> None:
            _fn(_ctx, _d, t_us)

        update.grid_native = sampler(TIMED, fn, ctx, d)  # the loop's grid in C
        self.update = update
        self._row_c = (lib.actors_row, ctx, 0, 0)

    def update_python(self, t_us: int) -> None:
        """Grid instant ``t_us``: the Python twin of ``actors_update`` (module notes)."""
        physics = self.physics
        base = physics.base_heading_xy() if self._waits else None
        for s, path, (geoms, local, _) in zip(self._states, self.paths, self._geoms):
            start, last = s.start_us, s.last_us
            since = last if last > start else start
            if t_us > since:
                dt = t_us - since
                if not self._blocked(s, base):
                    s.waited_us = 0
                elif s.waited_us < s.give_way_us:
                    s.waited_us += dt
                    dt = 0
                if dt > 0:
                    step = self._step(s, path, geoms.tolist(), local.tolist(), dt)
                    s.held_us += dt - step
                    s.progress_us += step
            s.last_us = t_us
            x, y, yaw = path.pose_at(s.progress_us / 1e6)
            s.pose[0], s.pose[1], s.pose[2] = x, y, yaw
            physics.set_mocap_pose(s.mocap, x, y, yaw)

    def _step(self, s: _State, path, geoms: list, local: list, dt: int) -> int:
        """``actor_step`` of actors.c: the walking time (us, at most ``dt``) that does not press the
        actor into the robot by more than ``touch_m``; once touching it, none until a whole step is
        free."""
        nx, ny, _ = path.pose_at((s.progress_us + dt) / 1e6)
        mx, my = nx - s.pose[0], ny - s.pose[1]
        d = self.physics.data
        p = d.xpos[self._ctx.base_body]
        bx, by = s.pose[0] - p[0], s.pose[1] - p[1]
        reach = s.reach_m + self._ctx.robot_reach_m + math.sqrt(mx * mx + my * my) + 0.01
        if len(geoms) > ACTOR_GEOMS or bx * bx + by * by > reach * reach:
            s.touching = 0
            return dt
        keep = [(d.geom_xpos[g].copy(), d.geom_xmat[g].copy()) for g in geoms]
        gap = gap_after(
            self.physics, self._robot, geoms, local, path.pose_at((s.progress_us + dt) / 1e6)
        )
        step = dt
        if s.touching:
            if gap < 0.0:
                step = 0
            else:
                s.touching = 0
        elif gap < -s.touch_m:
            s.touching = 1
            lo, hi = 0, dt
            for _ in range(BISECTIONS):
                if hi - lo <= 1:
                    break
                mid = lo + (hi - lo) // 2
                if (
                    gap_after(
                        self.physics,
                        self._robot,
                        geoms,
                        local,
                        path.pose_at((s.progress_us + mid) / 1e6),
                    )
                    >= -s.touch_m
                ):
                    lo = mid
                else:
                    hi = mid
            step = lo
        for g, (x, r) in zip(geoms, keep):
            d.geom_xpos[g], d.geom_xmat[g] = x, r
        return step

    def _blocked(self, s: _State, base) -> bool:
        """``actor_blocked`` of actors.c: the robot's footprint nearer than ``stop_m`` ahead of the
        actor."""
        stop = s.stop_m
        if stop <= 0.0:
            return False
        bx, by, hx, hy = base
        n = math.sqrt(hx * hx + hy * hy)
        cs, sn = hx / n, hy / n
        ax, ay, yaw = s.pose
        dx, dy = ax - bx, ay - by
        lx, ly = cs * dx + sn * dy, cs * dy - sn * dx
        hl, hw = self._ctx.half_len_m, self._ctx.half_wid_m
        qx = -hl if lx < -hl else (hl if lx > hl else lx)
        qy = -hw if ly < -hw else (hw if ly > hw else ly)
        gx, gy = qx - lx, qy - ly
        dist2 = gx * gx + gy * gy
        if dist2 >= stop * stop:
            return False
        wx, wy = cs * gx - sn * gy, sn * gx + cs * gy
        return wx * math.cos(yaw) + wy * math.sin(yaw) > 0.0 or dist2 == 0.0

    def reset(self, t_us: int) -> None:
        """Each actor back at the start of its path at grid instant ``t_us`` (a waited start is not
        waited again)."""
        for s, path in zip(self._states, self.paths):
            s.progress_us, s.last_us = 0, t_us
            x, y, yaw = path.pose_at(0.0)
            s.pose[0], s.pose[1], s.pose[2] = x, y, yaw
            self.physics.set_mocap_pose(s.mocap, x, y, yaw)

    def poses(self) -> list[tuple[float, float, float]]:
        """Each actor's pose as last placed: ``(x_m, y_m, yaw_rad)``."""
        return [tuple(s.pose) for s in self._states[: len(self.actors)]]

    def held_s(self) -> list[float]:
        """Each actor's walking time lost to touching the robot so far, s."""
        return [s.held_us / US for s in self._states[: len(self.actors)]]

    def progress_s(self) -> list[float]:
        """Each actor's walking time so far, s (less than the time since its start when it
        waited)."""
        return [s.progress_us / US for s in self._states[: len(self.actors)]]

    def pose_rows(self, period_us: int = PUBLISH_PERIOD_US) -> GridRows:
        """A grid sampler keeping every ``period_us`` the poses (x_m, y_m, yaw_rad per actor) just
        placed (``actors_row`` in C, the same values); put it after :attr:`update`."""

        def row() -> list[float]:
            return [v for s in self._states[: len(self.actors)] for v in s.pose]

        return GridRows(3 * len(self.actors), period_us, row, self._row_c, start_us=0)


class ActorPoses:
    """Publishes ``actors/poses`` (module notes) from ``motion``'s pose rows; appends the rows'
    keeper to ``samplers`` (after the motion's sampler, which must be in it already)."""

    def __init__(
        self, motion: ActorMotion, clock, bus, samplers: list, period_us: int = PUBLISH_PERIOD_US
    ):
        from amr_twin.ros.geometry_messages import PoseArray

        self.clock, self.bus, self.n = clock, bus, len(motion.actors)
        self.rows = motion.pose_rows(period_us)
        samplers.insert(samplers.index(motion.update) + 1, self.rows)
        self._ready: deque = deque()
        self.seq = 0
        bus.advertise(TOPIC, PoseArray)
        first = -(-clock.now_us // period_us) * period_us
        self._handle = clock.schedule_every(
            first, period_us, self._publish_next, publishes=(TOPIC,)
        )

    def _publish_next(self) -> None:
        from amr_twin.ros.geometry_messages import Point, Pose, PoseArray, Quaternion
        from amr_twin.ros.messages import Header, Time

        now = self.clock.now_us
        if not self._ready:
            self._ready.extend(self.rows.take().tolist())
        while (
            self._ready and self._ready[0][0] < now
        ):  # rows of instants no event publishes (a late start)
            self._ready.popleft()
        if not self._ready or self._ready[0][0] != now:
            raise RuntimeError(f"actor poses at t_us={now} were not kept on the loop's grid")
        row = self._ready.popleft()
        self.seq += 1
        poses = [
            Pose(Point(row[1 + 3 * i], row[2 + 3 * i], 0.0), Quaternion.from_yaw(row[3 + 3 * i]))
            for i in range(self.n)
        ]
        self.bus.publish(TOPIC, PoseArray(Header(self.seq, Time.from_us(now), FRAME), poses))
