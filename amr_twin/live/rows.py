"""The 100 Hz rows of a live twin, as :meth:`amr_twin.recording.recorder.Recorder.series` gives
them.

A grid sampler keeps, at each instant of the record grid, the loop's sensor row, the pin
row the recorder will pair with it and the battery's state as its accounting left it (what
the recorder keeps too); :meth:`LiveRows.take` turns the rows the clock has passed into the
series' columns with the recorder's own formula (:func:`~amr_twin.sim.plant.motor_currents_a`),
so that a live viewer shows the numbers the ``.mcap`` and the ``.rrd`` hold, bit for bit.
"""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np

from amr_twin.sim.plant import motor_currents_a
from amr_twin.recording.recorder import RAD_S_TO_RPM
from amr_twin.analysis.se2 import yaws_of_quaternions


class LiveRows:
    """Grid rows of ``twin`` kept until taken (attach before the twin runs)."""

    def __init__(self, twin):
        self.twin = twin
        self._rows: list[
            tuple[int, np.ndarray, np.ndarray, list]
        ] = []  # t_us, sensors, pins, battery
        self.count = 0
        """Rows taken so far (the index of the next row in the run's series)."""
        self._observables = twin.observables
        twin.on_grid(self._on_grid)
        self._on_grid(twin.t_phys_us)

    def _on_grid(self, t_us: int) -> None:
        seen = self._observables
        self._rows.append((t_us, seen.loop_sensors(), seen.drive(), seen.battery()))

    def take(self, t_us: int) -> SimpleNamespace | None:
        """The rows at or before ``t_us`` as series columns (None if there are none): ``t_us`` (n,)
        int, ``t_s``, ``true_rpm`` (n, 2), ``pose`` (n, 3) x, y, yaw, ``pwm_counts`` (n, 2),
        ``current_a`` (n, 2), ``battery_v``, ``battery_a``, ``battery_soc`` (n,), ``index`` (n,) the
        rows' places in the run."""
        n = 0
        while n < len(self._rows) and self._rows[n][0] <= t_us:
            n += 1
        if n == 0:
            return None
        rows, self._rows = self._rows[:n], self._rows[n:]
        t_us_arr = np.array([r[0] for r in rows], np.int64)
        t = t_us_arr * 1e-6
        sensors = np.array([r[1] for r in rows])
        pins = np.array([r[2] for r in rows])
        battery = np.array([r[3] for r in rows])  # terminal_v, current_a, soc
        mode, voltage = pins[:, 4:6].astype(int), pins[:, 6:8]
        current = motor_currents_a(self.twin.cfg, voltage, sensors[:, 2:4], mode)
        index = np.arange(self.count, self.count + n)
        self.count += n
        return SimpleNamespace(
            t_us=t_us_arr,
            t_s=t,
            true_rpm=sensors[:, 2:4] * RAD_S_TO_RPM,
            pose=np.column_stack(
                [sensors[:, 4], sensors[:, 5], yaws_of_quaternions(sensors[:, 7:11])]
            ),
            pwm_counts=pins[:, 0:2].astype(int),
            current_a=current,
            battery_v=battery[:, 0],
            battery_a=battery[:, 1],
            battery_soc=battery[:, 2],
            index=index,
        )
