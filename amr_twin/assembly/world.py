"""A world and the robots on it: :class:`World`, the physics stepped between the events of one
clock, sampled on one record grid, with the actors, the collision monitor and the divergence
checks, and each robot's parts on the same loop (:mod:`amr_twin.assembly.robot`).

After dm_control's composer (an arena holds the entities attached to it; the environment steps
the physics between their callbacks): the world builds its robots from
:class:`~amr_twin.assembly.robot.RobotSpec` items, each robot's parts attach themselves to the
world's hooks, clock and bus, and :meth:`World.advance_to_us` runs them all.

Reasons and measurements: docs/explanation/architecture.md#amr_twinassemblyworld.
"""

from __future__ import annotations

import math
from operator import attrgetter
from typing import Sequence

from amr_twin.assembly.robot import Robot, RobotSpec
from amr_twin.base.clock import VirtualClock
from amr_twin.ros.bus import Bus
from amr_twin.sim.collisions import CollisionMonitor
from amr_twin.sim.grid_loop import GridLoop
from amr_twin.sim.hooks import Hooks

US = 1_000_000
_VERSION = attrgetter("version")


class World(Hooks):
    """``physics`` (:class:`~amr_twin.sim.physics.Physics`, every robot in it) and the robots of
    ``robots`` on one clock and bus; build it, then :meth:`advance` it in simulated time.

    Args:
        physics: the built, settled physics of the world and its robots.
        robots: one spec per robot, in the order they are built and stepped.
        grid_every: physics steps between two instants of the record grid (``on_grid``).
        check_every_s: period of the divergence checks (``Physics.check``), s.
        stop_on_collision: halt the loop at the first collision.
        actors: :class:`amr_twin.model.actors.Actor` items moved on the grid.
        actor_cfg: the configuration the actors' motion reads (``actors:``, the robot's
            footprint); needed with actors only.
    """

    def __init__(
        self,
        physics,
        robots: Sequence[RobotSpec],
        *,
        grid_every: int,
        check_every_s: float,
        stop_on_collision: bool = False,
        actors: tuple = (),
        actor_cfg=None,
    ):
        self.physics = physics
        self.clock = VirtualClock()
        self.bus = Bus(self.clock)
        """The world's message bus (one ROS graph); a robot's parts publish on it."""
        self._init_hooks(self.bus)
        self.dt_us = int(round(physics.timestep_s * US))
        self.t_phys_us = 0
        self.grid_every = int(grid_every)
        self.grid_us = self.dt_us * self.grid_every
        self.check_every_us = int(check_every_s * US)
        self.actors_move = bool(actors)
        """Actors move in the world (people, pallet jacks): a component may sample faster."""
        lone = len(robots) == 1
        self.robots: list[Robot] = [
            Robot(self, spec, self.bus if lone else Bus(self.clock)) for spec in robots
        ]
        """The robots, in the order of ``robots`` (their bodies hooked first, their sensors after
        the world's own samplers); with several, each on a bus of its own (one ROS namespace)."""
        monitors = [
            CollisionMonitor(r.physics, stop=stop_on_collision, listeners=self._collision_hooks)
            for r in self.robots
        ]
        self.collisions = monitors[0] if lone else None
        """The lone robot's collision monitor; None with several (each robot's
        ``Robot.collisions``, all of them in :meth:`collision_records`)."""
        self._buses = [self.bus] if lone else [r.bus for r in self.robots]
        self._lookahead_memo: dict[tuple[str, ...], int] = {}
        self._lookahead_stamp = -1
        width = max(r.physics.loop_columns.stop for r in self.robots)
        self._grid = GridLoop(physics, self.samplers, self.grid_every, self.dt_us, width=width)
        self.halted = False
        self.stopped = False
        """:meth:`stop` was called: :meth:`advance` returns at once (a run ended from outside, e.g.
        a signal)."""
        self.actors = None
        """The actors' motion (:class:`amr_twin.sim.actors.ActorMotion`), None without actors."""
        if actors:
            from amr_twin.sim.actors import ActorMotion, ActorPoses

            self.actors = ActorMotion(physics, tuple(actors), actor_cfg)
            self.on_grid(self.actors.update)
            self._actor_poses = ActorPoses(self.actors, self.clock, self.bus, self.samplers)
        for monitor in monitors:
            self.on_grid(monitor)
        for robot, monitor in zip(self.robots, monitors):
            robot.equip(self._grid, monitor)
        self._next_check_us = self.check_every_us
        for sampler in self.samplers:
            sampler(0)
        for robot in self.robots:
            robot.inject_faults(self)
        for robot in self.robots:
            robot.start()

    # -- time -----------------------------------------------------------------------
    @property
    def t_s(self) -> float:
        """The clock's time, s."""
        return self.clock.now_us / US

    def advance(self, duration_s: float) -> None:
        """Run the world for ``duration_s`` simulated seconds."""
        if not (math.isfinite(duration_s) and duration_s >= 0):
            raise ValueError(f"duration_s: {duration_s} must be a finite number >= 0")
        self.advance_to_us(self.clock.now_us + int(round(duration_s * US)))

    def advance_to_us(self, t_end_us: int) -> None:
        """Run to the clock time ``t_end_us``: the physics stepped to each synced event, the hall
        edges delivered, the events run, each robot's pins applied when they changed (and at each
        divergence check), the ``on_event`` hook called."""
        clock, robots, event_hooks = self.clock, self.robots, self._event_hooks
        deliver = robots[0].deliver_edges if len(robots) == 1 else self._deliver_edges
        lookahead = self.bus.lookahead_us if len(robots) == 1 else self._lookahead_us
        last_pins = [None] * len(robots)
        while clock.now_us < t_end_us and not self.halted and not self.stopped:
            t_evt = min(clock.next_synced_event_us(), t_end_us, self._next_check_us)
            t_evt = clock.physics_horizon_us(t_evt, lookahead)
            if self.t_phys_us < t_evt:
                nstep = -(-(t_evt - self.t_phys_us) // self.dt_us)
                self._step_physics(nstep)
                if self.halted:  # a sampler stopped the physics early
                    t_evt = max(clock.now_us, min(t_evt, self.t_phys_us))
            deliver(t_evt)
            clock.run_until(t_evt)
            check = t_evt >= self._next_check_us
            for i, robot in enumerate(robots):
                actuation = robot.actuation
                key = actuation.levels()
                if key != last_pins[i] or check:
                    actuation.apply(self.t_phys_us)
                    last_pins[i] = key
            if check:
                self.physics.check()
                self._next_check_us += self.check_every_us
            for fn in event_hooks:
                fn(self.t_phys_us)

    def on_message(self, tap, topics: tuple[str, ...] | None = None):
        """The hook of :class:`~amr_twin.sim.hooks.Hooks` on the world's bus; ValueError (one line)
        in a fleet, whose robots speak on buses of their own (each robot's: a fleet's recording
        taps them, :mod:`amr_twin.recording.fleet_capture`)."""
        if len(self.robots) > 1:
            raise ValueError(
                "on_message: a fleet's robots speak on buses of their own (robot.bus); "
                "record a fleet with amr_twin.recording.fleet_capture.attach_fleet"
            )
        return super().on_message(tap, topics)

    def _lookahead_us(self, topics: tuple[str, ...]) -> int:
        """The least :meth:`~amr_twin.ros.bus.Bus.lookahead_us` of ``topics`` over the robots'
        buses (a publishing event may be any robot's)."""
        stamp = sum(map(_VERSION, self._buses))
        if stamp != self._lookahead_stamp:  # a subscription came or went
            self._lookahead_memo.clear()
            self._lookahead_stamp = stamp
        best = self._lookahead_memo.get(topics)
        if best is None:
            best = min(bus.lookahead_us(topics) for bus in self._buses)
            self._lookahead_memo[topics] = best
        return best

    def collision_records(self) -> list[dict]:
        """Every robot's collisions (:meth:`~amr_twin.sim.collisions.Collision.as_dict`, tagged
        with the robot in a fleet), in the order they began."""
        hits = [c for robot in self.robots for c in robot.collisions.collisions]
        return [c.as_dict() for c in sorted(hits, key=lambda c: c.t_s)]

    def stop(self) -> None:
        """End the run at the next event (safe from a signal handler): :meth:`advance` returns from
        then on."""
        self.stopped = True

    def reset_world(self) -> None:
        """The actors back at the start of their paths, each robot at its start pose, at rest."""
        if self.actors is not None:
            self.actors.reset(self.clock.now_us)
        for robot in self.robots:
            robot.set_pose(*robot.start_xy_yaw)

    def _step_physics(self, nstep: int) -> None:
        """Step ``nstep`` times, sampling on the record grid
        (:class:`~amr_twin.sim.grid_loop.GridLoop`); each robot solves its hall edges from the
        chunk's rows (:meth:`~amr_twin.assembly.robot.Robot.take_rows`)."""
        grid = self._grid
        k, ts, rows, grid_t, grid_rows = grid.run(self.t_phys_us // self.dt_us, nstep)
        self.halted = grid.halted
        self.t_phys_us = k * self.dt_us
        if grid_t:
            for fn in self._grid_row_hooks:
                fn(grid_t, grid_rows)
        for robot in self.robots:
            robot.take_rows(ts, rows)

    def _deliver_edges(self, t_until_us: int) -> None:
        """Every robot's pending SC edges up to ``t_until_us``, in time order across the robots
        (:func:`deliver_in_time_order`)."""
        deliver_in_time_order(self.clock, self.robots, t_until_us)


def deliver_in_time_order(clock, robots: Sequence, t_until_us: int) -> None:
    """Hand each robot's pending SC edges (``robot.pending``: ``(t_us, wheel)`` in time order) up to
    ``t_until_us`` to its firmware's ISR, all robots' edges in time order (ties: robot order), the
    clock run to each edge's instant first."""
    due = []
    for k, robot in enumerate(robots):
        pending, n = robot.pending, 0
        for t_e, wheel in pending:
            if t_e > t_until_us:
                break
            due.append((t_e, k, wheel))
            n += 1
        del pending[:n]
    due.sort()
    for t_e, k, wheel in due:
        clock.run_until(max(t_e, clock.now_us))
        robots[k].firmware.on_sc_edge(wheel)
