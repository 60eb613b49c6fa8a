"""The capture of a world of several robots: :func:`attach_fleet`, one
:class:`~amr_twin.recording.rerun_capture.Capture` and one
:class:`~amr_twin.recording.recorder.Recorder` a robot.

Each robot of a fleet speaks on a bus of its own and has its own columns of the loop's rows
(:class:`~amr_twin.assembly.world.World`); :class:`RobotView` shows one robot to the capture and
the recorder as a lone twin: its bus, its observables, its columns of the grid rows, the world's
grid and clock. The writers are :mod:`amr_twin.recording.fleet_mcap` and
:mod:`amr_twin.recording.fleet_rrd`.
"""

from __future__ import annotations

from dataclasses import dataclass

from amr_twin.recording.recorder import Recorder
from amr_twin.recording.rerun_capture import Capture
from amr_twin.ros.robot_namespace import RobotNamespace


class RobotView:
    """The robot ``robot`` of ``world`` (a :class:`~amr_twin.assembly.world.World`) with the hooks
    and attributes of a lone :class:`~amr_twin.assembly.twin.Twin` that the capture, the recorder,
    the event log and the live rows read (module notes); ``name`` its ROS namespace (None: its
    name in the model)."""

    def __init__(self, world, robot, name: str | None = None):
        self.world, self.robot = world, robot
        self.name = robot.name if name is None else name
        """The robot's name, its namespace (``amr-2``)."""
        self.prefix = robot.physics.prefix
        """Its names' prefix in the model (``amr-2/``)."""
        self.cfg, self.bus = robot.spec.cfg, robot.bus
        self.observables, self.sensors = robot.observables, robot.sensors
        self.collisions, self.faults = robot.collisions, robot.faults
        self.grid_every, self.grid_us = world.grid_every, world.grid_us
        self._columns = robot.physics.loop_columns

    @property
    def t_phys_us(self) -> int:
        """The world's physics time, us."""
        return self.world.t_phys_us

    def on_grid(self, sampler):
        """The world's grid hook."""
        return self.world.on_grid(sampler)

    def on_actuation(self, fn):
        """The world's actuation hook (any robot's pins: ``fn`` reads this robot's)."""
        return self.world.on_actuation(fn)

    def on_message(self, tap, topics: tuple[str, ...] | None = None):
        """Tap the robot's own bus."""
        self.robot.bus.add_tap(tap, topics=topics)
        return tap

    def on_grid_rows(self, fn):
        """Call ``fn(t_us, rows)`` with this robot's columns of the world's grid rows."""
        columns = self._columns

        def robot_rows(t_us, rows) -> None:
            fn(t_us, [row[columns] for row in rows])

        self.world.on_grid_rows(robot_rows)
        return robot_rows

    def unhook(self, fn) -> None:
        """Remove ``fn`` from the world's hooks or the robot's bus."""
        if self.robot.bus.has_tap(fn):
            self.robot.bus.remove_tap(fn)
        else:
            self.world.unhook(fn)


@dataclass
class RobotCapture:
    """One robot's part of a fleet's capture: its view, namespace, capture and recorder."""

    view: RobotView
    namespace: RobotNamespace
    capture: Capture
    recorder: Recorder


def robot_bodies(model, prefix: str) -> list[int]:
    """Ids of the bodies named ``prefix...`` (one robot's) in ``model``."""
    import mujoco

    names = [
        mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_BODY, b) or "" for b in range(model.nbody)
    ]
    return [b for b, name in enumerate(names) if name.startswith(prefix)]


def moving_fixtures(model, prefixes) -> list[int]:
    """Ids of the bodies but the world's that belong to no robot (the actors)."""
    import mujoco

    return [
        b
        for b in range(1, model.nbody)
        if not (mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_BODY, b) or "").startswith(prefixes)
    ]


def attach_fleet(world, body_hz: float = 30.0, names=None) -> list[RobotCapture]:
    """Start capturing every robot of ``world`` (before it runs): a :class:`RobotCapture` each, in
    the world's order, named ``names`` (None: their names in the model); the first robot's
    capture keeps the actors' poses too. The world must draw its robots (a fleet's world always
    does; a lone twin with ``visuals``)."""
    model = world.physics.model
    prefixes = tuple(r.physics.prefix for r in world.robots)
    out = []
    names = [None] * len(world.robots) if names is None else list(names)
    for i, robot in enumerate(world.robots):
        view = RobotView(world, robot, names[i])
        bodies = robot_bodies(model, view.prefix)
        if i == 0:
            bodies += moving_fixtures(model, prefixes)
        capture = Capture(view, body_hz, prefix=view.prefix, bodies=sorted(bodies))
        out.append(RobotCapture(view, RobotNamespace(view.name), capture, Recorder(view)))
    return out


class SeenEvents:
    """Entries appended to ``events`` (a list another thread appends to: the fleet manager's
    ``dispatcher.events``) stamped with the simulated time at which the world saw them: a pacer
    sink (:meth:`flush` at each 20 ms tick). :attr:`stamped`: ``(t_us, entry)`` in order."""

    def __init__(self, events: list):
        self._events, self._seen = events, 0
        self.stamped: list[tuple[int, dict]] = []

    def flush(self, t_us: int) -> None:
        """Stamp the entries appended since the last tick with ``t_us``."""
        n = len(self._events)
        self.stamped += [(t_us, e) for e in self._events[self._seen : n]]
        self._seen = n

    def close(self) -> None:
        """Nothing to release."""
