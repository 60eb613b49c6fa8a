"""The simulation loop's hooks: where recorders, live views, bridges, navigation and experiments attach.

:class:`~amr_twin.sim.loop.Twin` is a :class:`Hooks`; what runs downstream of the loop subscribes
here and reads the twin's :class:`~amr_twin.sim.observables.Observables`, instead of reaching into
its physics, plant, hall sensors or firmware or tapping its bus (tests/sim/test_hooks.py holds the
recorder, the fault injector, the live views and the ROS 1 bridge to it). A node (a PC-side program:
odometry, teleop, the navigation stack) sits on the bus itself, as it would on a ROS graph.
The hooks, in the order the loop calls them within one of its steps (:data:`HOOKS`):

``on_grid(sampler)``
    per record-grid instant (every 10 ms of simulated time, while the physics steps between two
    events): ``sampler(t_us)`` with the physics at ``t_us``; a sampler returning True halts the
    twin there. A sampler with a C form (``sampler.grid_native``, :mod:`amr_twin.sim.grid_steps`:
    a :class:`~amr_twin.sim.grid_steps.GridRows`, e.g. :func:`amr_twin.sim.named_index.value_rows`)
    keeps the grid loop in C; one without makes that loop run in Python, slower.
``on_grid_rows(fn)``
    after each chunk of physics: ``fn(t_us, rows)``, the chunk's grid instants (list of int, us) and
    the loop sensors' rows there (lists of :data:`~amr_twin.model.robot_spec.LOOP_SENSOR_DIM` floats:
    what the ``loop_sensors`` observable reads); both lists are shared: read, do not change.
``on_event(fn)``
    at each instant the physics stopped at (a synced clock event: a timer tick, a rosserial frame, a
    divergence check, the end of an ``advance``), after the clock's events up to it ran and the pins
    were applied to the plant: ``fn(t_us)``, the physics time.
``on_actuation(fn)``
    when the plant took the pins anew (new levels, the periodic re-application with the battery's
    voltage, a fault or the e-stop: :class:`~amr_twin.sim.actuation.Actuation`): ``fn(t_us)``; the
    ``drive`` observable has the levels, modes and phase voltages then in force.
``on_message(tap, topics=None)``
    per message published on the bus: ``tap(topic, msg, t_us)`` (:meth:`amr_twin.ros.bus.Bus.add_tap`),
    for ``topics`` only when given.
``on_collision(fn)``
    at the first contact of each collision (in a grid sampler: the physics at that instant):
    ``fn(collision)``, a :class:`~amr_twin.sim.collisions.Collision`; the ``collisions`` observable
    lists them all.

:meth:`Hooks.unhook` removes a subscriber from whichever hook holds it.
"""

from __future__ import annotations

from typing import Callable

HOOKS = ("on_grid", "on_grid_rows", "on_event", "on_actuation", "on_message", "on_collision")
"""Every hook the loop defines (docs/architecture.md names each; a test checks it)."""


class Hooks:
    """The hook lists of a twin and the methods that subscribe to them (module notes)."""

    def _init_hooks(self, bus) -> None:
        self._bus = bus
        self.samplers: list = []
        """The grid samplers, in the order they run (the ``on_grid`` hook; the twin's own first)."""
        self._grid_row_hooks: list = []
        self._event_hooks: list = []
        self._actuation_hooks: list = []
        self._collision_hooks: list = []

    def on_grid(self, sampler: Callable[[int], object]) -> Callable:
        """Run ``sampler(t_us)`` at every grid instant, after those hooked before it; returns it."""
        self.samplers.append(sampler)
        return sampler

    def on_grid_rows(self, fn: Callable[[list, list], None]) -> Callable:
        """Call ``fn(t_us, rows)`` after each chunk with its grid instants and loop-sensor rows; returns it."""
        self._grid_row_hooks.append(fn)
        return fn

    def on_event(self, fn: Callable[[int], None]) -> Callable:
        """Call ``fn(t_us)`` after the clock's events of each instant ran and the pins were applied; returns it."""
        self._event_hooks.append(fn)
        return fn

    def on_actuation(self, fn: Callable[[int], None]) -> Callable:
        """Call ``fn(t_us)`` whenever the plant takes the pins anew; returns it."""
        self._actuation_hooks.append(fn)
        return fn

    def on_message(self, tap: Callable[[str, object, int], None], topics: tuple[str, ...] | None = None) -> Callable:
        """Call ``tap(topic, msg, t_us)`` for each message published on the bus (``topics`` only); returns it."""
        self._bus.add_tap(tap, topics=topics)
        return tap

    def on_collision(self, fn: Callable[[object], None]) -> Callable:
        """Call ``fn(collision)`` at each collision's first contact; returns it."""
        self._collision_hooks.append(fn)
        return fn

    def unhook(self, fn: Callable) -> None:
        """Remove ``fn`` from every hook that holds it (ValueError if none does)."""
        found = False
        for hooks in (self.samplers, self._grid_row_hooks, self._event_hooks, self._actuation_hooks,
                      self._collision_hooks):
            while fn in hooks:
                hooks.remove(fn)
                found = True
        if self._bus.has_tap(fn):
            self._bus.remove_tap(fn)
            found = True
        if not found:
            raise ValueError(f"{fn!r} is hooked to nothing")
