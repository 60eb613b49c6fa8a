"""Inject parsed faults (:mod:`amr_twin.sim.faults`) into a running :class:`~amr_twin.sim.loop.Twin`.

Reasons and measurements: docs/architecture.md#amr_twinsimfault_injector."""

from __future__ import annotations

import dataclasses
from typing import Callable

import numpy as np

from amr_twin.sim.faults import WHEEL_NAMES, Fault

US = 1_000_000
WINDOW_S = 0.5
"""Averaging window of the speeds before a fault and at the end of the run, s."""


@dataclasses.dataclass(frozen=True)
class FaultTargets:
    """What the faults act on, handed over by the twin that owns them."""

    hall: object        # sensors.hall.HallSensors
    physics: object     # amr_twin.sim.physics.Physics: jam_wheel, lift_wheel, wheel_angles_rad
    link: object        # amr_twin.ros.rosserial.RosserialLink
    bus: object         # amr_twin.ros.bus.Bus: intercept
    actuation: object   # amr_twin.sim.actuation.Actuation
    t_us: Callable[[], int]  # the physics time now, us


class FaultInjector:
    """Schedules ``faults`` on ``clock`` and applies them to ``targets``; ``hooks`` the twin's
    (:class:`~amr_twin.sim.hooks.Hooks`). Built by the twin when ``TwinOptions.faults`` is set."""

    def __init__(self, faults: tuple[Fault, ...], clock, hooks, targets: FaultTargets):
        self.targets = targets
        self.faults = tuple(faults)
        self._saved: dict[int, object] = {}
        self._last: dict[str, object] = {}        # last IMU messages published (imu-stuck)
        self._times: dict[str, list[int]] = {}     # publication times of the sensor topics
        self._imu_values: list[tuple] = []         # (gyro, accel) of each imu/data_raw message
        if any(f.kind in ("imu-stuck", "lidar-dead") for f in self.faults):
            hooks.on_message(self._tap)
        for i, fault in enumerate(self.faults):
            t_us = int(round(fault.t_s * US))
            if t_us <= clock.now_us:  # at the start: in force before anything is sent
                self._set(i, True)
            else:
                clock.schedule(t_us, lambda i=i: self._set(i, True))
            if fault.until_s is not None:
                clock.schedule(int(round(fault.until_s * US)), lambda i=i: self._set(i, False))

    def _tap(self, topic: str, msg, t_us: int) -> None:
        if topic in ("imu/data_raw", "imu/mag", "scan"):
            self._times.setdefault(topic, []).append(t_us)
            self._last[topic] = msg
            if topic == "imu/data_raw":
                g, a = msg.angular_velocity, msg.linear_acceleration
                self._imu_values.append((g.x, g.y, g.z, a.x, a.y, a.z))

    # -- apply / clear ------------------------------------------------------------------
    def _set(self, i: int, on: bool) -> None:
        fault, to = self.faults[i], self.targets
        w = fault.wheel
        if fault.kind == "hall-dead":
            sensors = range(3) if fault.value == "all" else ["abc".index(fault.value)]
            angle = float(to.physics.wheel_angles_rad()[w])
            for k in sensors:
                to.hall.set_stuck(w, k, on, angle)
        elif fault.kind == "hall-chatter":
            to.hall.glitch_rate_hz[w] = float(fault.value) if on else 0.0
        elif fault.kind == "motor-stall":
            to.physics.jam_wheel(w, on)
        elif fault.kind == "wheel-lifted":
            to.physics.lift_wheel(w, on)
        elif fault.kind == "rosserial-loss":
            self._swap(i, on, to.link, "loss_prob", float(fault.value))
        elif fault.kind == "rosserial-latency":
            self._swap(i, on, to.link, "extra_latency_us", int(round(float(fault.value) * 1000)))
        elif fault.kind == "lidar-dead":
            to.bus.intercept("scan", (lambda msg: None) if on else None)
        elif fault.kind == "imu-stuck":
            for topic in ("imu/data_raw", "imu/mag"):
                held = self._last.get(topic)
                to.bus.intercept(topic, _repeat(held) if on and held is not None else None)
        elif fault.kind == "battery-sag":
            to.actuation.sag_battery(float(fault.value) if on else 0.0, to.t_us())
        elif fault.kind == "battery-cut":
            to.actuation.cut_supply(on, to.t_us())
        elif fault.kind == "estop":
            to.actuation.press_estop(on, to.t_us())

    def _swap(self, i: int, on: bool, obj, attr: str, value) -> None:
        if on:
            self._saved[i] = getattr(obj, attr)
            setattr(obj, attr, value)
        else:
            setattr(obj, attr, self._saved.pop(i))

    # -- report ---------------------------------------------------------------------------
    def report(self, series) -> list[dict]:
        """Each fault (:meth:`Fault.describe`) with ``effect``: what the wheels and sensors did.

        Per wheel: mean true speed in the :data:`WINDOW_S` before the fault and at the
        end of the run, the largest true speed after the fault (RPM, signed +
        forward), the wheel speeds the firmware published after the fault (count and
        last value) and the PWM counts at the end. For the robot: the distance it
        travelled after the fault, m. For sensor faults: the messages published after it
        (and, for the IMU, how many distinct gyro/accelerometer readings they carried).
        """
        from amr_twin.recording.recorder import signed_published

        t = series.t_s
        out = []
        for fault in self.faults:
            after = t >= fault.t_s
            before = (t < fault.t_s) & (t >= fault.t_s - WINDOW_S)
            end = t >= t[-1] - WINDOW_S
            wheels = {}
            for w, name in enumerate(WHEEL_NAMES):
                rpm = series.true_rpm[:, w]
                pub = signed_published(series, w)
                pub_after = pub[pub[:, 0] >= fault.t_s] if len(pub) else pub
                peak = rpm[after][np.argmax(np.abs(rpm[after]))] if after.any() else float("nan")
                wheels[name] = {
                    "true_rpm_before": _mean(rpm[before]), "true_rpm_end": _mean(rpm[end]),
                    "true_rpm_peak_after": round(float(peak), 3),
                    "published_after": int(len(pub_after)),
                    "last_published_rpm": round(float(pub[-1, 1]), 3) if len(pub) else None,
                    "last_published_t_s": round(float(pub[-1, 0]), 4) if len(pub) else None,
                    "pwm_counts_end": int(series.pwm_counts[-1, w]),
                }
            xy = series.pose[after, :2]
            effect = {"wheels": wheels,
                      "moved_after_m": round(float(np.sum(np.hypot(*np.diff(xy, axis=0).T))), 4) if len(xy) > 1 else 0.0}
            for topic in ("scan", "imu/data_raw"):
                if topic in self._times:
                    times = np.array(self._times[topic]) * 1e-6
                    effect[f"{topic}_published_after"] = int(np.sum(times >= fault.t_s))
            if "imu/data_raw" in self._times:
                times = np.array(self._times["imu/data_raw"]) * 1e-6
                after_values = [v for v, t_m in zip(self._imu_values, times) if t_m >= fault.t_s]
                effect["imu/data_raw_distinct_values_after"] = len(set(after_values))
            out.append(dict(fault.describe(), effect=effect))
        return out


def _mean(values: np.ndarray):
    return round(float(np.mean(values)), 3) if len(values) else None


def _repeat(held):
    """An interception that publishes ``held``'s values under each new message's header."""
    def stuck(msg):
        return dataclasses.replace(held, header=msg.header)
    return stuck
