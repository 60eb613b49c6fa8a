"""The 100 Hz rows the bridge puts on ``/twin/*`` and ``/battery_state``, kept as the recorder keeps
them:
:class:`RowFeed`.

The loop-sensor rows come from the ``on_grid_rows`` hook, the drive from ``on_actuation`` (the drive
in force during the step that ends at a row: the last change before it) and the battery from a grid
sampler with a C form (:meth:`amr_twin.sim.observables.Observables.battery_rows`; the last
accounting at or before a row), so the twin's grid loop stays in C (:mod:`amr_twin.live.rows`'
Python grid sampler sends it back to Python: ~25 % more CPU for a twin with sensors). The columns
are :class:`amr_twin.recording.recorder.Recorder`'s, with its formulas, bit for bit
(``tests/ros1/test_row_feed.py``)."""

from __future__ import annotations

import bisect
from types import SimpleNamespace

import numpy as np

from amr_twin.recording.recorder import RAD_S_TO_RPM
from amr_twin.sim.plant import motor_currents_a


class RowFeed:
    """The rows of ``twin`` from now on (its state now, then each grid instant's), kept until
    :meth:`take`."""

    def __init__(self, twin):
        self.twin = twin
        seen = twin.observables
        self._grid_us = twin.grid_us
        self._t: list[int] = [twin.t_phys_us]  # the row now, then the grid's
        self._rows: list = [seen.loop_sensors()]
        self._pin_t: list[int] = [twin.t_phys_us]
        self._pins: list[list[float]] = [list(seen.drive())]
        self._battery = twin.on_grid(
            seen.battery_rows()
        )  # a row at each grid instant, as the loop's
        self._battery(twin.t_phys_us)
        twin.on_grid_rows(self._extend)
        twin.on_actuation(self._pins_changed)

    def _extend(self, t_us: list, rows: list) -> None:
        self._t += t_us
        self._rows += rows

    def _pins_changed(self, t_us: int) -> None:
        row = list(self.twin.observables.drive())
        if self._pin_t[-1] == t_us:
            self._pins[-1] = row
        else:
            self._pin_t.append(t_us)
            self._pins.append(row)

    def take(self, t_us: int) -> SimpleNamespace | None:
        """The rows at or before ``t_us`` (None if none): ``t_us`` (n,) int, ``true_rpm`` (n, 2),
        ``pwm_counts`` (n, 2), ``current_a`` (n, 2), ``battery_v``, ``battery_a``, ``battery_soc``
        (n,), ``index`` (n,) the rows' places in the run's series (one a grid instant from t =
        0)."""
        n = bisect.bisect_right(self._t, t_us)
        if n == 0:
            return None
        times = np.array(self._t[:n], np.int64)
        rows = np.array(self._rows[:n], float)
        del self._t[:n], self._rows[:n]
        k = np.searchsorted(np.array(self._pin_t), times, side="left") - 1
        pins = np.array(self._pins, float)[np.maximum(k, 0)]
        keep = max(
            int(k[-1]), 0
        )  # the drive in force at the last row may be in force at the next ones
        del self._pin_t[:keep], self._pins[:keep]
        battery = self._battery.take_until(t_us)
        at = np.maximum(np.searchsorted(battery[:, 0], times, side="right") - 1, 0)
        mode, voltage = pins[:, 4:6].astype(int), pins[:, 6:8]
        return SimpleNamespace(
            t_us=times,
            true_rpm=rows[:, 2:4] * RAD_S_TO_RPM,
            pwm_counts=pins[:, 0:2].astype(int),
            current_a=motor_currents_a(self.twin.cfg, voltage, rows[:, 2:4], mode),
            battery_v=battery[at, 1],
            battery_a=battery[at, 2],
            battery_soc=battery[at, 3],
            index=times // self._grid_us,
        )
