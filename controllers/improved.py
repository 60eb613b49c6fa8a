"""Improved wheel firmware, same interface and pin semantics as the thesis port.

Reasons and measurements: docs/explanation/firmware.md#amr_twincontrollersimproved."""

from __future__ import annotations

import math
from collections import deque
from typing import Sequence

from amr_twin.base.clock import VirtualClock
from amr_twin.base.pins import HIGH, LOW

from amr_twin.controllers.arduino import ArduinoRuntime
from amr_twin.controllers.firmware_params import ImprovedParams, Publish

FORWARD, BACKWARD, STOP = 1, -1, 0


class ImprovedFirmware:
    """Per-edge speed sensing and a 50 Hz anti-windup PI on the emulated Arduino.

    Parameters
    ----------
    clock : VirtualClock
        Shared clock.
    publish : callable
        ``publish(topic, rpm)``; ``wheel0_Vel``/``wheel1_Vel``, RPM >= 0.
    edges_per_rev : int
        SC changes per wheel revolution (``wheel.sc_edges_per_rev``).
    params : ImprovedParams
        Gains, rates and windows.
    """

    def __init__(
        self,
        clock: VirtualClock,
        publish: Publish,
        edges_per_rev: int,
        params: ImprovedParams | None = None,
    ):
        self.p = p = params or ImprovedParams()
        self.edges_per_rev = int(edges_per_rev)
        self.clock, self._publish = clock, publish
        self.rt = ArduinoRuntime(clock, p.board)
        self.pins = self.rt.pins
        self._edges = (deque(maxlen=p.window_edges + 1), deque(maxlen=p.window_edges + 1))
        self._count = [0, 0]  # SC edges since start (the SC output has no direction)
        self._position = [0.0, 0.0]  # edges the published samples account for
        self._published_us = 0
        self._isr = (lambda: self._edge(0), lambda: self._edge(1))
        self.motion = [STOP, STOP]
        self.setpoint_rpm = [0.0, 0.0]  # commanded magnitude
        self.reference_rpm = [0.0, 0.0]  # ramped, signed (+ = forward)
        self.integral_rpm = [0.0, 0.0]
        self.speed_rpm = [0.0, 0.0]  # measured magnitude
        self._residual = [0.0, 0.0]
        self._ticks = 0
        self._dt_s = p.pi_period_us * 1e-6

    # -- Firmware protocol ---------------------------------------------------------
    def connect(self, bus, link) -> bool:
        """No UART of its own: the loop bridges wheel_Command and the published speeds."""
        return False

    def start(self) -> None:
        """setup(): wheels braked, SC interrupts attached for good, Timer1 at the PI rate."""
        b = self.p.board
        for i in range(2):
            self._brake(i)
            self.rt.digitalWrite(b.stop_pins[i], HIGH)
            self.rt.digitalWrite(b.dir_pins[i], HIGH)
            self.rt.attachInterrupt(self.rt.digitalPinToInterrupt(b.speed_pins[i]), self._isr[i])
        self._published_us = self.rt.micros()
        self.rt.timer_initialize(self.p.pi_period_us, self._tick)

    def on_wheel_command(self, data: Sequence[float]) -> None:
        """wheel_Command ``[motionL, speedL, motionR, speedR]``; handled at once (no delay())."""
        values = tuple(float(x) for x in data)
        self.rt.post_main(lambda: self._command(values))

    def on_sc_edge(self, wheel: int) -> None:
        """SC change of ``wheel``: timestamped by its ISR."""
        self.rt.external_edge(wheel)

    # -- main context ----------------------------------------------------------------
    def _command(self, data: Sequence[float]) -> None:
        b = self.p.board
        for i in range(2):
            motion, speed = int(data[2 * i]), abs(data[2 * i + 1])
            driving = self.motion[i] != STOP and self.setpoint_rpm[i] > 0
            self.motion[i] = motion
            self.setpoint_rpm[i] = speed if motion != STOP else 0.0
            if motion == STOP:
                self._brake(i)
            elif speed == 0:
                self.rt.analogWrite(b.pwm_pins[i], 0)
                self.rt.digitalWrite(b.brake_pins[i], LOW)
                self.rt.digitalWrite(b.stop_pins[i], LOW)
                self._reset(i)
            else:
                if not driving:  # ramp from where the wheel is, in the DIR direction
                    self._reset(i)
                    self.reference_rpm[i] = self._dir(i) * self.speed_rpm[i]
                self.rt.digitalWrite(b.brake_pins[i], LOW)
                self.rt.digitalWrite(b.stop_pins[i], HIGH)

    def _brake(self, i: int) -> None:
        b = self.p.board
        self.rt.analogWrite(b.pwm_pins[i], 0)
        self.rt.digitalWrite(b.brake_pins[i], HIGH)
        self._reset(i)

    def _reset(self, i: int) -> None:
        self.reference_rpm[i] = 0.0
        self.integral_rpm[i] = 0.0
        self._residual[i] = 0.0

    def _dir(self, i: int) -> int:
        return 1 if self.pins[i].dir_level == HIGH else -1

    # -- speed -------------------------------------------------------------------------
    def _edge(self, i: int) -> None:
        """SC change of wheel ``i`` (ISR): timestamped for the speed, counted for the published
        mean."""
        self._edges[i].append(self.rt.micros())
        self._count[i] += 1

    def mean_rpm(self, i: int, now_us: int, dt_us: int) -> float:
        """Mean speed magnitude of wheel ``i`` over the last ``dt_us`` (since the previous sample),
        RPM: the SC edges counted since then and, at ``extrapolate_above_rpm`` or more (where even
        the brake lets the wheel roll several edges on, so the next edge is sure to come), the part
        of an edge rolled since the last one, from the per-edge speed; never behind what the
        previous sample accounted for."""
        p, edges = self.p, self._edges[i]
        position = float(self._count[i])
        if edges and self.speed_rpm[i] >= p.extrapolate_above_rpm:
            since_us = (now_us - edges[-1]) & 0xFFFFFFFF
            position += min(self.speed_rpm[i] * self.edges_per_rev * since_us / 60e6, 1.0)
        position = max(position, self._position[i])
        rpm = (position - self._position[i]) * 60e6 / (self.edges_per_rev * max(dt_us, 1))
        self._position[i] = position
        return rpm

    def measured_rpm(self, i: int) -> float:
        """Speed magnitude of wheel ``i`` from its recent SC edges, RPM."""
        p, edges = self.p, self._edges[i]
        if len(edges) < 2:
            return 0.0
        now = self.rt.micros()
        last = edges[-1]
        since_us = (now - last) & 0xFFFFFFFF
        if since_us > p.zero_speed_timeout_us:
            edges.clear()
            return 0.0
        n = 0
        for k in range(len(edges) - 2, -1, -1):
            if (last - edges[k]) & 0xFFFFFFFF > p.window_us and n >= 1:
                break
            n += 1
        if n >= 3:
            n -= n % 3
        span_us = (last - edges[-1 - n]) & 0xFFFFFFFF
        rpm = 60e6 * n / (self.edges_per_rev * max(span_us, 1))
        if since_us > 0:
            rpm = min(rpm, 60e6 / (self.edges_per_rev * since_us))
        return rpm

    # -- Timer1 ISR --------------------------------------------------------------------
    def _tick(self) -> None:
        p, b, dt = self.p, self.p.board, self._dt_s
        for i in range(2):
            speed = self.speed_rpm[i] = self.measured_rpm(i)
            if self.motion[i] == STOP or self.setpoint_rpm[i] == 0:
                continue
            target = self.motion[i] * self.setpoint_rpm[i]
            step = p.ramp_rate_rpm_per_s * dt
            ref = self.reference_rpm[i] + min(max(target - self.reference_rpm[i], -step), step)
            self.reference_rpm[i] = ref
            if ref != 0 and (ref > 0) != (self._dir(i) > 0):
                self.rt.digitalWrite(b.dir_pins[i], HIGH if ref > 0 else LOW)
                self.integral_rpm[i] = 0.0
            r = abs(ref)
            error = r - speed
            raw = p.feedforward_gain * r + p.kp * error + self.integral_rpm[i]
            u = min(max(raw, p.min_control_rpm), p.max_control_rpm)
            hold = ref != target or abs(error) > p.integral_band_rpm
            if not hold and (u == raw or (raw > u and error < 0) or (raw < u and error > 0)):
                self.integral_rpm[i] += p.ki * error * dt
            counts = u / p.max_vel_rpm * 255.0
            if p.dither_pwm:
                out = math.floor(counts + self._residual[i])
                self._residual[i] += counts - out
            else:
                out = round(counts)
            self.rt.analogWrite(b.pwm_pins[i], out)
        self._ticks += 1
        if self._ticks % p.publish_every_ticks == 0:
            if p.publish_mean:
                now = self.rt.micros()
                dt_us = (now - self._published_us) & 0xFFFFFFFF
                self._published_us = now
                rpm = (self.mean_rpm(0, now, dt_us), self.mean_rpm(1, now, dt_us))
            else:
                rpm = self.speed_rpm
            self._publish("wheel0_Vel", rpm[0])
            self._publish("wheel1_Vel", rpm[1])
