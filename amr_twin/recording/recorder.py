"""Time series of a run: what the loop sees every step, and what the bus carries.

A consumer of the loop's hooks (:mod:`amr_twin.sim.hooks`) and observables: ``on_grid_rows``
hands over the loop sensors' rows on the record grid (wheel angles and speeds, base pose);
``on_actuation`` the drive in force, which only changes at events; a grid sampler after the
battery's accounting (``on_grid``, :attr:`Recorder.battery`) keeps the battery's state as the
accounting left it (terminal voltage, current, charge); ``on_message`` keeps every published
wheel speed, wheel command and odometry message with its delivery time.

Whoever runs a twin and wants its series attaches a recorder (:func:`attach_recorder`) before the
twin runs; the twin itself builds none.
"""

from __future__ import annotations

import math
import weakref
from dataclasses import dataclass, field

import numpy as np

from amr_twin.sim.plant import motor_currents_a
from amr_twin.analysis.se2 import yaw_of_quaternion, yaws_of_quaternions

RAD_S_TO_RPM = 60.0 / (2.0 * math.pi)


@dataclass
class RunSeries:
    """Arrays of one run. Shapes: n recorded rows; k published samples."""

    t_s: np.ndarray  # (n,)
    wheel_angle_rad: np.ndarray  # (n, 2) left, right
    true_rpm: np.ndarray  # (n, 2) signed, + rolling forward
    pose: np.ndarray  # (n, 3) x_m, y_m, yaw_rad (world)
    pwm_counts: np.ndarray  # (n, 2) analogWrite value on the driver's PWM pin
    direction: np.ndarray  # (n, 2) +1 DIR high (forward), -1 low
    mode: np.ndarray  # (n, 2) 0 drive, 1 coast, 2 brake
    battery_v: np.ndarray  # (n,) terminal voltage at the instant (the battery's accounting)
    voltage_v: np.ndarray  # (n, 2) phase voltage the driver applies (0 braking or coasting)
    current_a: np.ndarray  # (n, 2) motor (phase) current, + driving forward
    battery_a: np.ndarray  # (n,) the pack's current: drivers and auxiliary load (the accounting's)
    battery_soc: np.ndarray  # (n,) state of charge, 0..1 (the grid's accounting)
    published: dict[
        int, np.ndarray
    ]  # wheel -> (k, 2) rows t_s, |rpm| as received on the PC (signed_published)
    odom: np.ndarray  # (k, 4) t_s, x_m, y_m, yaw_rad (odom frame)
    commands: list[tuple[float, list[float]]] = field(default_factory=list)


def signed_published(series: RunSeries, wheel: int) -> np.ndarray:
    """(k, 2) t_s, published RPM signed by the wheel's commanded direction (the last non-zero
    motion code of wheel_Command at or before the sample, forward before any): the SC output
    the firmware times has no direction, the wheel odometry node signs it the same way."""
    pub = series.published[wheel]
    direction = 1.0
    cmds = [(t, c[2 * wheel]) for t, c in series.commands]
    signs, i = np.empty(len(pub)), 0
    for k, t in enumerate(pub[:, 0]):
        while i < len(cmds) and cmds[i][0] <= t:
            if cmds[i][1]:
                direction = 1.0 if cmds[i][1] > 0 else -1.0
            i += 1
        signs[k] = direction
    return np.column_stack([pub[:, 0], signs * np.abs(pub[:, 1])]) if len(pub) else pub


_recorders: "weakref.WeakKeyDictionary" = weakref.WeakKeyDictionary()


def attach_recorder(twin) -> "Recorder":
    """The :class:`Recorder` of ``twin``: the one attached before, else one attached now (its series
    starts at the present instant: attach before the twin runs)."""
    return _recorders.get(twin) or Recorder(twin)


def recorder_of(twin) -> "Recorder | None":
    """The :class:`Recorder` attached to ``twin``, or None."""
    return _recorders.get(twin)


class Recorder:
    """Collects a run's time series from the hooks of ``twin`` (a
    :class:`~amr_twin.assembly.twin.Twin`) from the present instant on; use :func:`attach_recorder`
    (one recorder a twin)."""

    def __init__(self, twin) -> None:
        self.twin = twin
        self.every = twin.grid_every
        self._t: list[np.ndarray] = []
        self._rows: list[np.ndarray] = []
        self._pin_t: list[int] = []
        self._pins: list[np.ndarray] = []
        self._published: dict[int, list[tuple[float, float]]] = {0: [], 1: []}
        self._odom: list[tuple[float, float, float, float]] = []
        self.commands: list[tuple[float, list[float]]] = []
        self.battery = twin.on_grid(twin.observables.battery_rows())
        """Grid sampler (hooked after the battery's accounting): rows ``t_us, terminal_v, current_a,
        soc`` (:meth:`amr_twin.sim.observables.Observables.battery`)."""
        self._handlers = {
            "wheel0_Vel": self._on_wheel0,
            "wheel1_Vel": self._on_wheel1,
            "wheel_Command": self._on_command,
            "odom": self._on_odom,
        }
        twin.on_message(self._tap, topics=tuple(self._handlers))  # not called for IMU, scan, tf
        twin.on_actuation(self.pins_changed)
        twin.on_grid_rows(self.extend_grid)
        _recorders[twin] = self
        self.battery(
            twin.t_phys_us
        )  # the present instant: the battery, the drive in force, the loop sensors
        self.pins_changed(twin.t_phys_us)
        self.sample()

    def _tap(self, topic: str, msg, t_us: int) -> None:
        self._handlers[topic](msg, t_us * 1e-6)

    def _on_wheel0(self, msg, t_s: float) -> None:
        self._published[0].append((t_s, msg.data))

    def _on_wheel1(self, msg, t_s: float) -> None:
        self._published[1].append((t_s, msg.data))

    def _on_command(self, msg, t_s: float) -> None:
        self.commands.append((t_s, [float(v) for v in msg.data]))

    def _on_odom(self, msg, t_s: float) -> None:
        q = msg.pose.pose.orientation
        yaw = yaw_of_quaternion(q.w, q.x, q.y, q.z)
        self._odom.append((t_s, msg.pose.pose.position.x, msg.pose.pose.position.y, yaw))

    def pins_changed(self, t_us: int) -> None:
        """The plant took the pins at physics time ``t_us`` (``on_actuation``): keep the drive in
        force."""
        row = np.array(self.twin.observables.drive())
        if self._pin_t and self._pin_t[-1] == t_us:
            self._pins[-1] = row
        else:
            self._pin_t.append(t_us)
            self._pins.append(row)

    def sample(self) -> None:
        """Record the present state as one row (at the start of a run)."""
        self._t.append(np.array([self.twin.t_phys_us]))
        self._rows.append(np.array([self.twin.observables.loop_sensors()]))

    def extend_grid(self, t_us: list[int], rows: list[list[float]]) -> None:
        """Keep rows already on the record grid (lists from the loop; stacked lazily)."""
        self._t.append(t_us)
        self._rows.append(rows)

    def series(self) -> RunSeries:
        t_us = np.concatenate([np.asarray(t, np.int64) for t in self._t])
        t = t_us * 1e-6
        rows = np.vstack([np.asarray(r) for r in self._rows])
        # pins in force during the step that ends at each row: the last change before it
        idx = np.searchsorted(np.array(self._pin_t), t_us, side="left") - 1
        pins = np.array(self._pins)[np.clip(idx, 0, None)]
        pose = np.column_stack([rows[:, 4], rows[:, 5], yaws_of_quaternions(rows[:, 7:11])])
        published = {w: np.array(v, float).reshape(-1, 2) for w, v in self._published.items()}
        mode, voltage = pins[:, 4:6].astype(int), pins[:, 6:8]
        current = motor_currents_a(self.twin.cfg, voltage, rows[:, 2:4], mode)
        # the battery as its accounting left it at each row's instant (the last at or before it)
        kept = self.battery.rows
        at = np.clip(np.searchsorted(kept[:, 0], t_us, side="right") - 1, 0, None)
        battery_v, battery_a, soc = kept[at, 1], kept[at, 2], kept[at, 3]
        return RunSeries(
            t_s=t,
            wheel_angle_rad=rows[:, 0:2],
            true_rpm=rows[:, 2:4] * RAD_S_TO_RPM,
            pose=pose,
            pwm_counts=pins[:, 0:2].astype(int),
            direction=pins[:, 2:4].astype(int),
            mode=mode,
            battery_v=battery_v,
            voltage_v=voltage,
            current_a=current,
            battery_a=battery_a,
            battery_soc=soc,
            published=published,
            odom=np.array(self._odom, float).reshape(-1, 4),
            commands=list(self.commands),
        )
