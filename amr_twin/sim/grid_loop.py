"""The physics stepped between two of the loop's events, sampled on the record grid:
:class:`GridLoop`.

:meth:`amr_twin.assembly.twin.Twin.advance_to_us` brings the physics to each synced event with
:meth:`GridLoop.run`: ``mj_step`` to each record-grid instant (every ``every`` steps, 10 ms),
the loop sensors' row kept there (:data:`~amr_twin.model.robot_spec.LOOP_SENSOR_DIM`: wheel
angles and speeds, base position and orientation) and the grid samplers run
(:attr:`amr_twin.assembly.twin.Twin.samplers`, the loop's per-instant hook), then the remaining
steps to the event. The grid loop runs in C (:mod:`amr_twin.sim.grid_steps`) when every grid
sampler has a C form (:meth:`_grid_in_c`), else here (:meth:`_grid_in_python`, its Python
twin: the same steps, rows and sampler calls, the same bits).

A grid sampler that returns True ends the chunk at that instant and halts the loop
(:attr:`GridLoop.halted`). In a world of several robots one loop steps them all and its row holds
every robot's loop sensors (``width``: :attr:`amr_twin.sim.settled_physics.Fleet.loop_width`;
each robot's columns: :attr:`amr_twin.sim.physics.Physics.loop_columns`).


Part of the physics layer (``PHYSICS_LAYER``): it steps MjData and reads its sensor row.
"""

from __future__ import annotations

from itertools import islice

import mujoco

from amr_twin.model.robot_spec import LOOP_SENSOR_DIM
from amr_twin.sim.grid_steps import grid_stepper

PHYSICS_LAYER = True

SENSORS_OFF = int(mujoco.mjtDisableBit.mjDSBL_SENSOR)
"""MuJoCo's flag that skips the sensors: set on the steps between grid instants (no one reads
sensordata there; the state is the same to the bit)."""


class GridLoop:
    """Chunks of ``physics`` (:class:`~amr_twin.sim.physics.Physics`) with ``samplers`` run every
    ``every`` steps of ``dt_us``, rows of the first ``width`` sensor values; the C grid loop unless
    its helper is missing."""

    def __init__(
        self, physics, samplers: list, every: int, dt_us: int, width: int = LOOP_SENSOR_DIM
    ):
        self.samplers = samplers
        self.every, self.dt_us = int(every), int(dt_us)
        self.halted = False
        """True once a grid sampler returned True (the loop steps no further)."""
        self._m, self._d = physics.model, physics.data
        self._stepper = grid_stepper(physics, width, self.every, self.dt_us)
        """The grid loop in C (:mod:`amr_twin.sim.grid_steps`), None without its helper."""
        self._sensors = physics.data.sensordata[:width]  # a view: MjData's buffers stay put
        self.last_row = self._sensors.tolist()
        """The loop sensors' row where the last chunk ended (at the twin's start: the start's)."""

    def row(self) -> list[float]:
        """The loop sensors' row now (per robot LOOP_SENSOR_DIM values: wheel angles L, R rad;
        speeds L, R rad/s; base position m; base quaternion w, x, y, z)."""
        return self._sensors.tolist()

    def run(self, k0: int, nstep: int) -> tuple[int, list, list, list, list]:
        """Step ``nstep`` times from step ``k0``, sampling on the record grid (module notes).

        Returns ``(k, ts, rows, grid_t, grid_rows)``: the step reached (``k0 + nstep``, or the
        halting instant's), the instants (us) and loop-sensor rows of the chunk's start, its grid
        instants and its end (plain lists: the hall edges are solved between them), and those of the
        grid instants alone."""
        dt = self.dt_us
        k_end = k0 + nstep
        grid_t, grid_rows = [], []
        stepper = self._stepper
        if stepper is not None and stepper.use(self.samplers):
            k = self._grid_in_c(stepper, k0, k_end, grid_t, grid_rows)
        else:
            k = self._grid_in_python(k0, k_end, grid_t, grid_rows)
        if self.halted:  # a sampler stopped the physics at step k
            k_end = k
        ts, rows = [k0 * dt, *grid_t], [self.last_row, *grid_rows]
        if k < k_end:
            mujoco.mj_step(self._m, self._d, k_end - k)
            k = k_end
            ts.append(k * dt)
            rows.append(self._sensors.tolist())
        self.last_row = rows[-1]
        return k, ts, rows, grid_t, grid_rows

    def _grid_in_python(self, k: int, k_end: int, grid_t: list, grid_rows: list) -> int:
        """From step ``k``, step to each grid instant up to step ``k_end``, keeping its time and
        row in ``grid_t`` and ``grid_rows`` and running the grid samplers there; the step reached
        (the last instant's, or ``k``). A sampler returning True halts the loop at its instant."""
        m, d, dt, every = self._m, self._d, self.dt_us, self.every
        sensors, step, samplers = self._sensors, mujoco.mj_step, self.samplers
        opt = m.opt
        flags = opt.disableflags
        for mark in range((k // every + 1) * every, k_end + 1, every):
            if mark - k > 1:  # MuJoCo's sensors on the last step only, as grid_steps.c
                opt.disableflags = flags | SENSORS_OFF
                try:
                    step(m, d, mark - k - 1)
                finally:
                    opt.disableflags = flags
            step(m, d, 1)
            k = mark
            t = k * dt
            row = sensors.tolist()
            grid_t.append(t)
            grid_rows.append(row)
            stop = False
            for sampler in samplers:
                if sampler(t):
                    stop = True
            if stop:
                self.halted = True
                break
        return k

    def _grid_in_c(self, stepper, k: int, k_end: int, grid_t: list, grid_rows: list) -> int:
        """:meth:`_grid_in_python` with the grid loop in C (:mod:`amr_twin.sim.grid_steps`): the
        same steps, rows and sampler calls. An instant a sampler hands back runs the rest of its
        samplers here; if one then has no C form (a collision opened) the chunk ends in Python."""
        dt, every = self.dt_us, self.every
        first = (k // every + 1) * every
        nmarks = (k_end - first) // every + 1 if first <= k_end else 0
        done = 0
        while done < nmarks:
            mark = first + done * every
            reached, handoff = stepper.run(mark - k, nmarks - done, mark * dt)
            k = mark + (reached - 1) * every
            grid_t.extend(range(mark * dt, k * dt + 1, every * dt))
            grid_rows.extend(stepper.rows[:reached].tolist())
            done += reached
            if handoff >= 0:
                t = k * dt
                stop = bool(stepper.resume[handoff](t))
                for sampler in islice(
                    self.samplers, handoff + 1, None
                ):  # the live list, as the Python loop walks it
                    if sampler(t):
                        stop = True
                if stop:
                    self.halted = True
                    return k
                if done < nmarks and not stepper.use(self.samplers):
                    return self._grid_in_python(k, k_end, grid_t, grid_rows)
        return k
