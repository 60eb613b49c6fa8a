"""The simulation loop's hooks: where recorders, live views, bridges, navigation and experiments
attach.

Reasons and measurements: docs/explanation/architecture.md#amr_twinsimhooks."""

from __future__ import annotations

from typing import Callable

HOOKS = ("on_grid", "on_grid_rows", "on_event", "on_actuation", "on_message", "on_collision")
"""Every hook the loop defines (docs/explanation/architecture.md names each; a test checks it)."""


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
        """Call ``fn(t_us, rows)`` after each chunk with its grid instants and loop-sensor rows;
        returns it."""
        self._grid_row_hooks.append(fn)
        return fn

    def on_event(self, fn: Callable[[int], None]) -> Callable:
        """Call ``fn(t_us)`` after the clock's events of each instant ran and the pins were applied;
        returns it."""
        self._event_hooks.append(fn)
        return fn

    def on_actuation(self, fn: Callable[[int], None]) -> Callable:
        """Call ``fn(t_us)`` whenever the plant takes the pins anew; returns it."""
        self._actuation_hooks.append(fn)
        return fn

    def on_message(
        self, tap: Callable[[str, object, int], None], topics: tuple[str, ...] | None = None
    ) -> Callable:
        """Call ``tap(topic, msg, t_us)`` for each message published on the bus (``topics`` only);
        returns it."""
        self._bus.add_tap(tap, topics=topics)
        return tap

    def on_collision(self, fn: Callable[[object], None]) -> Callable:
        """Call ``fn(collision)`` at each collision's first contact; returns it."""
        self._collision_hooks.append(fn)
        return fn

    def unhook(self, fn: Callable) -> None:
        """Remove ``fn`` from every hook that holds it (ValueError if none does)."""
        found = False
        for hooks in (
            self.samplers,
            self._grid_row_hooks,
            self._event_hooks,
            self._actuation_hooks,
            self._collision_hooks,
        ):
            while fn in hooks:
                hooks.remove(fn)
                found = True
        if self._bus.has_tap(fn):
            self._bus.remove_tap(fn)
            found = True
        if not found:
            raise ValueError(f"{fn!r} is hooked to nothing")
