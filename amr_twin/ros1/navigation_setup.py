"""The navigation stack of a run on the ROS 1 graph: ``amr-twin run ... --sensors --ros1``
(:class:`RunNavigation`).

Checked before the twin is built (:meth:`RunNavigation.checked`, one line each): the action server's
Debian packages, the world's map (a world with no obstacle has none) and the start pose on it; the
run goes on without the stack when one is missing, saying why. On the built twin,
:meth:`RunNavigation.attach` puts the stack of ``run goto``
(:func:`amr_twin.navigation.stack.attach`: the EKF of odometry, gyro and UWB, the navigator idle
until a goal, its plan, map and costmap messages) on the bus, without a diff-drive node of its own
(the run brings one for ``cmd_vel``); :meth:`RunNavigation.serve` puts it on the graph
(:class:`~amr_twin.ros1.navigation_server.NavigationServer`). The run's own commands yield to it:
:class:`YieldingCommand`. ``run goto ... --ros1`` and a mission's ``goals:`` with ``--ros1``, where
the stack drives to the run's goals: :class:`GoalsOnGraph`.
"""

from __future__ import annotations

from dataclasses import dataclass, field


@dataclass(frozen=True)
class YieldingCommand:
    """A run's command (:class:`amr_twin.assembly.command.Command`) that is not sent while the
    navigator drives to a goal.

    ``say(line)`` tells of a command left out; ``send`` returns 0 then (nothing was refused)."""

    command: object
    navigator: object
    say: object = print

    def send(self, twin) -> int:
        if self.navigator.active is None:
            return self.command.send(twin)
        self.say(
            f"ros1: the run's {self.command.kind} command at t = {twin.t_s:.2f} s not sent: a "
            f"move_base goal "
            "is active (the navigator drives)"
        )
        return 0

    def describe(self) -> dict:
        return self.command.describe()


@dataclass
class RunNavigation:
    """The static map of a run's world and, once attached, the navigator and the goals' checker."""

    cfg: object
    static: object
    navigator: object = None
    checker: object = None
    server: object = field(default=None, repr=False)

    @classmethod
    def checked(cls, cfg, world: str, start) -> "RunNavigation":
        """The world's map with ``start`` (None: the world's start) on it; ValueError (one line)
        otherwise."""
        import numpy as np

        from amr_twin.model.worlds import MapError, default_start
        from amr_twin.ros1.navigation_server import missing
        from amr_twin.navigation.stack import true_map

        problem = missing()
        if problem:
            raise ValueError(f"--ros1 with --sensors: {problem}")
        try:
            static = true_map(cfg, world)
        except MapError as exc:
            raise ValueError(str(exc)) from None
        nav = cls(cfg, static)
        here = np.array((start or default_start(world))[:2], float)
        if not nav._checker().costmap.cells(here[None])[2][0]:
            raise ValueError(
                f"the start ({here[0]:g}, {here[1]:g}) lies outside the map of --world {world}: "
                f"give "
                "--start X_M,Y_M,YAW_DEG on it"
            )
        return nav

    def _checker(self):
        """A planner on the static map alone (the goals' check, as ``run goto`` checks its
        goals)."""
        from amr_twin.navigation.footprint import robot_footprint
        from amr_twin.navigation.planner import GlobalPlanner
        from amr_twin.navigation.stack import make_costmap

        if self.checker is None:
            self.checker = GlobalPlanner(
                make_costmap(self.static, robot_footprint(self.cfg), self.cfg.navigation)
            )
        return self.checker

    def attach(self, twin, seed: int = 0):
        """Put the stack on ``twin``'s bus, idle; returns the navigator."""
        from amr_twin.navigation.stack import NavigationOptions, attach

        self.navigator = attach(
            twin,
            self.cfg,
            self.static,
            NavigationOptions(goals=(), seed=seed),
            publish=True,
            drive=False,
        )
        return self.navigator

    def yielding(self, steps, say=print) -> list:
        """``steps`` (time, command) with each command yielding to the navigator's goals."""
        return [(t, YieldingCommand(command, self.navigator, say)) for t, command in steps]

    def serve(self, twin, pacer, say=print) -> None:
        """The navigator on the graph as move_base (after the ROS 1 session joined it)."""
        from amr_twin.ros1.navigation_server import NavigationServer

        self.server = NavigationServer(twin, pacer, self.navigator, self._checker(), say=say)


class GoalsOnGraph:
    """``run goto ... --ros1`` and a mission's ``goals:`` with ``--ros1``: ``twin`` on the graph
    (:class:`~amr_twin.ros1.session.Ros1Session`), and the navigator that drives it to the run's
    goals served as move_base as soon as it is on the bus (at the run's first instant): a goal of
    the action or on ``move_base_simple/goal`` preempts the run's own, as any new goal of the
    navigator does.

    ``static``: the run's static map (the goals' checks); ``pacer``: a live session's, or None for
    one of its own at ``rate`` (0: as fast as possible). :meth:`close` at the end of the run."""

    def __init__(self, twin, cfg, static, options, rate: float = 0.0, pacer=None, say=print):
        from amr_twin.ros1.session import Ros1Session, pacer_tick_us

        self._own_pacer = pacer is None
        if pacer is None:
            from amr_twin.live.pacer import Pacer

            pacer = Pacer(twin, rate, pacer_tick_us(rate))
        self.twin, self.pacer, self._say = twin, pacer, say
        self._navigation = RunNavigation(cfg, static)
        self.session = Ros1Session(twin, pacer, options, say=say)
        twin.clock.schedule(twin.clock.now_us, self._serve)

    def _serve(self) -> None:
        """The navigator is on the bus (the stack attaches it after the twin is built): serve it."""
        self._navigation.navigator = self.twin.navigator
        self._navigation.serve(self.twin, self.pacer, say=self._say)

    def close(self) -> None:
        """Stop the pacer (if it is this one's), the move_base server and the session."""
        if self._own_pacer:
            self.pacer.close()
        self.session.close()
