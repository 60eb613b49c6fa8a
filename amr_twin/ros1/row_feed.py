"""The 100 Hz rows the bridge puts on ``/twin/*`` and ``/battery_state``, kept as the recorder keeps
them:
:class:`RowFeed`.

The loop-sensor rows come from the ``on_grid_rows`` hook, the drive from ``on_actuation`` (the drive
in force during the step that ends at a row: the last change before it) and the battery from a grid
sampler with a C form (:meth:`amr_twin.sim.observables.Observables.battery_rows`; the last
accounting at or before a row), so the twin's grid loop stays in C (:mod:`amr_twin.live.rows`'
Python grid sampler sends it back to Python: ~25 % more CPU for a twin with sensors). The columns
are :class:`amr_twin.recording.recorder.Recorder`'s, with its formulas, bit for bit
(``tests/ros1/test_row_feed.py``). :meth:`RowFeed.blocks` gives a tick's rows as the bridge writes
them, in one call of ``frame_blocks.c`` (``fb_rows``: ~40 rows, the work of some 40 numpy calls),
or from :meth:`RowFeed.take` in Python: the same bytes (the same test, random rows, signed
zeros)."""

from __future__ import annotations

import bisect
import ctypes
from dataclasses import dataclass
from types import SimpleNamespace

import numpy as np

from amr_twin.base.native_build import address, c_array, open_helper
from amr_twin.recording.mcap_log import BATTERY_EVERY_ROWS
from amr_twin.recording.recorder import RAD_S_TO_RPM
from amr_twin.ros1.frame_blocks import (
    BATTERY_RECORD,
    C_SOURCE,
    battery_block,
    float64_rows_block,
)
from amr_twin.sim.plant import MODE_CODES, motor_currents_a


@dataclass(frozen=True)
class RowBlocks:
    """A tick's rows as blocks of TCPROS frames (:meth:`RowFeed.blocks`): the rows' instants
    ``t_us`` and their ``std_msgs/Float64MultiArray`` blocks ``true_rpm``, ``pwm_counts``,
    ``current_a``; the ``sensor_msgs/BatteryState`` block ``battery`` of the rows at ``battery_us``
    (every ``BATTERY_EVERY_ROWS``-th grid instant); ``battery_rows`` (n, 3) each row's battery V,
    A, state of charge."""

    t_us: list[int]
    true_rpm: bytes
    pwm_counts: bytes
    current_a: bytes
    battery_us: list[int]
    battery: bytes
    battery_rows: np.ndarray


class RowFeed:
    """The rows of ``twin`` from now on (its state now, then each grid instant's), kept until
    :meth:`take`."""

    def __init__(self, twin, native: bool = True):
        self.twin = twin
        cfg = twin.cfg
        lib, self.engine = open_helper(C_SOURCE, native)
        """``"C"`` or ``"Python (<why>)"``: what :meth:`blocks` runs."""
        self._fn = None if lib is None else lib.fb_rows
        if self._fn is not None:
            self._fn.restype = ctypes.c_int
            row = np.frombuffer(float64_rows_block(np.zeros((1, 2))), np.uint8).copy()
            bat = np.frombuffer(
                battery_block([0], [0.0], [0.0], [0.0], 0.0, [0.0]), np.uint8
            ).copy()
            fields = BATTERY_RECORD.template.dtype.fields
            bat_off = np.array([fields["stamp"][1], fields["values"][1]], np.int32)
            self._keep = (row, bat, bat_off)  # what the addresses point into
            self._c = (len(row), address(row), len(row) - 16, len(bat), address(bat), bat_off)
            self._motors = np.array(
                [
                    *(cfg.motor_left.ke_v_s_rad, cfg.motor_left.resistance_ohm),
                    cfg.motor_left.current_limit_a,
                    *(cfg.motor_right.ke_v_s_rad, cfg.motor_right.resistance_ohm),
                    cfg.motor_right.current_limit_a,
                    cfg.driver.brake_current_limit_a,
                ],
                np.float64,
            )
            p, i, q, d = ctypes.c_void_p, ctypes.c_int, ctypes.c_int64, ctypes.c_double
            self._fn.argtypes = [p, i, p, i, p, p, i, i, p, i, q, q, p, q, q, d, d]
            self._fn.argtypes += [p, p, p, p, i, i, p, p, i, p, p, p]
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

    def _take_raw(self, t_us: int) -> tuple | None:
        """The rows at or before ``t_us`` as kept (None if none), removed: their instants and rows,
        the drive rows with their instants, the battery rows."""
        n = bisect.bisect_right(self._t, t_us)
        if n == 0:
            return None
        times, rows = self._t[:n], self._rows[:n]
        del self._t[:n], self._rows[:n]
        pin_t, pins = np.array(self._pin_t, np.int64), np.array(self._pins, float)
        keep = max(  # the drive in force at the last row may be in force at the next ones
            bisect.bisect_left(self._pin_t, times[-1]) - 1, 0
        )
        del self._pin_t[:keep], self._pins[:keep]
        return (
            np.array(times, np.int64),
            np.array(rows, float),
            pin_t,
            pins,
            self._battery.take_until(t_us),
        )

    def take(self, t_us: int) -> SimpleNamespace | None:
        """The rows at or before ``t_us`` (None if none): ``t_us`` (n,) int, ``true_rpm`` (n, 2),
        ``pwm_counts`` (n, 2), ``current_a`` (n, 2), ``battery_v``, ``battery_a``, ``battery_soc``
        (n,), ``index`` (n,) the rows' places in the run's series (one a grid instant from t =
        0)."""
        raw = self._take_raw(t_us)
        return None if raw is None else self._columns(*raw)

    def _columns(self, times, rows, pin_t, pins, battery) -> SimpleNamespace:
        k = np.searchsorted(pin_t, times, side="left") - 1
        pins = pins[np.maximum(k, 0)]
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

    def blocks(self, t_us: int) -> RowBlocks | None:
        """The rows at or before ``t_us`` (None if none) as :class:`RowBlocks`: in one call of
        ``frame_blocks.c``'s ``fb_rows``, or (``native=False``, no helper) from :meth:`take` and
        the record blocks of :mod:`amr_twin.ros1.frame_blocks`: the same bytes."""
        raw = self._take_raw(t_us)
        if raw is None:
            return None
        if self._fn is None:
            return self._blocks_python(self._columns(*raw))
        return self._blocks_native(*raw)

    def _blocks_native(self, times, rows, pin_t, pins, battery) -> RowBlocks:
        n, cap = len(times), self.twin.cfg.battery.capacity_ah
        row_size, row_tmpl, row_off, bat_size, bat_tmpl, bat_off = self._c
        out = [np.empty(n * row_size, np.uint8) for _ in range(3)]
        bat = np.empty(n * bat_size, np.uint8)
        bat_t, vas = np.empty(n, np.int64), np.empty((n, 3))
        rows, pins, battery = (c_array(a, np.float64) for a in (rows, pins, battery))
        nbat = self._fn(
            address(times), n, address(rows), rows.shape[1], address(pin_t), address(pins),
            len(pin_t), pins.shape[1], address(battery), len(battery),
            self._grid_us, BATTERY_EVERY_ROWS, address(self._motors), MODE_CODES["brake"],
            MODE_CODES["coast"], cap, RAD_S_TO_RPM, *map(address, out), row_tmpl, row_size,
            row_off, address(bat), bat_tmpl, bat_size, address(bat_off), address(bat_t),
            address(vas),
        )  # fmt: skip
        if nbat < 0:  # no battery or drive row (the Python twin says so)
            return self._blocks_python(self._columns(times, rows, pin_t, pins, battery))
        return RowBlocks(
            times.tolist(), *(o.tobytes() for o in out), bat_t[:nbat].tolist(),
            bat[: nbat * bat_size].tobytes(), vas,
        )  # fmt: skip

    def _blocks_python(self, rows: SimpleNamespace) -> RowBlocks:
        at = rows.index % BATTERY_EVERY_ROWS == 0
        t, soc, cap = rows.t_us[at], rows.battery_soc[at], self.twin.cfg.battery.capacity_ah
        return RowBlocks(
            rows.t_us.tolist(),
            float64_rows_block(rows.true_rpm),
            float64_rows_block(rows.pwm_counts),
            float64_rows_block(rows.current_a),
            t.tolist(),
            battery_block(t, rows.battery_v[at], -rows.battery_a[at], soc * cap, cap, soc),
            np.stack([rows.battery_v, rows.battery_a, rows.battery_soc], axis=1),
        )
