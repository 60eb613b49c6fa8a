"""The capture of a world of several robots: :func:`attach_fleet`, one
:class:`~amr_twin.recording.rerun_capture.Capture` and one
:class:`~amr_twin.recording.recorder.Recorder` a robot.

Each robot of a fleet speaks on a bus of its own and has its own columns of the loop's rows
(:class:`~amr_twin.assembly.world.World`); a :class:`~amr_twin.assembly.robot_view.RobotView`
shows one robot to the capture and the recorder as a lone twin. The writers are
:mod:`amr_twin.recording.fleet_mcap` and :mod:`amr_twin.recording.fleet_rrd`.
"""

from __future__ import annotations

from dataclasses import dataclass

from amr_twin.assembly.robot_view import RobotView
from amr_twin.recording.recorder import Recorder
from amr_twin.recording.rerun_capture import Capture
from amr_twin.ros.robot_namespace import RobotNamespace


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
    names = [None] * len(world.robots) if names is None else list(names)
    views = [RobotView(world, robot, name) for robot, name in zip(world.robots, names)]
    model = views[0].observables.model
    prefixes = tuple(v.prefix for v in views)
    out = []
    for i, view in enumerate(views):
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
