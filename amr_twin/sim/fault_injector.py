"""Inject parsed faults (:mod:`amr_twin.sim.faults`) into a running
:class:`~amr_twin.assembly.twin.Twin`.

Reasons and measurements: docs/explanation/architecture.md#amr_twinsimfault_injector."""

from __future__ import annotations

import dataclasses
from typing import Callable

from amr_twin.sim.faults import Fault

US = 1_000_000


@dataclasses.dataclass(frozen=True)
class FaultTargets:
    """What the faults act on, handed over by the twin that owns them."""

    hall: object  # sensors.hall.HallSensors
    physics: object  # amr_twin.sim.physics.Physics: jam_wheel, support.lift_wheel, wheel_angles_rad
    link: object  # amr_twin.ros.rosserial.RosserialLink
    bus: object  # amr_twin.ros.bus.Bus: intercept
    actuation: object  # amr_twin.sim.actuation.Actuation
    t_us: Callable[[], int]  # the physics time now, us


class FaultInjector:
    """Schedules ``faults`` on ``clock`` and applies them to ``targets``; ``hooks`` the twin's
    (:class:`~amr_twin.sim.hooks.Hooks`). Built by a robot with faults (``RobotSpec.faults``)."""

    def __init__(self, faults: tuple[Fault, ...], clock, hooks, targets: FaultTargets):
        self.targets = targets
        self.faults = tuple(faults)
        self._saved: dict[int, object] = {}
        self._last: dict[str, object] = {}  # last IMU messages published (imu-stuck)
        self.sensor_times: dict[str, list[int]] = {}  # publication times of the sensor topics, us
        self.imu_values: list[tuple] = []  # (gyro, accel) of each imu/data_raw message
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
            self.sensor_times.setdefault(topic, []).append(t_us)
            self._last[topic] = msg
            if topic == "imu/data_raw":
                g, a = msg.angular_velocity, msg.linear_acceleration
                self.imu_values.append((g.x, g.y, g.z, a.x, a.y, a.z))

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
            to.physics.support.lift_wheel(w, on)
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


def _repeat(held):
    """An interception that publishes ``held``'s values under each new message's header."""

    def stuck(msg):
        return dataclasses.replace(held, header=msg.header)

    return stuck
