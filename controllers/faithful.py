"""Port of the thesis Arduino firmware (listings 4.7-4.12), quirks included.

C names are kept where the listing prints them (``Motor.driveNoAcc``,
``PI_Control``, ``speedChangeInt``) so the port reads against the thesis.
Reconstructed parts (not printed: ``computeSpeedFromSignal``, ``Motor.stop``/
``start``/``forward``/``backward``, the wheel_Command callback, ``PICallBack``,
``setup``/``loop``) are explained in docs/explanation/firmware.md. Each quirk sits behind a
switch of :class:`~amr_twin.controllers.firmware_params.FaithfulParams`.

Contexts as on the board: ``PICallBack`` and ``PI_Control`` run in the Timer1
ISR, ``speedChangeInt`` in the INT4/INT5 ISRs, the wheel_Command callback in
main context (``node.spinOnce()`` in ``loop()``), where its ramp ``delay()``
blocks ``loop()`` while interrupts keep firing.
"""

from __future__ import annotations

from typing import Sequence

from amr_twin.base.clock import VirtualClock
from amr_twin.base.pins import HIGH, LOW

from amr_twin.controllers.arduino import ArduinoRuntime, MainTask
from amr_twin.controllers.firmware_params import FaithfulParams, Publish

FORWARD, BACKWARD, STOP = 1, -1, 0  # listing 4.7


def _int16(value: int) -> int:
    """C ``int`` on AVR: the low 16 bits, two's complement."""
    value &= 0xFFFF
    return value - 0x10000 if value >= 0x8000 else value


class Motor:
    """One wheel's driver pins and state (listing 4.8)."""

    def __init__(self, rt: ArduinoRuntime, p: FaithfulParams, wheel: int):
        b = p.board
        self.rt, self.p = rt, p
        self.PIN_STOP, self.PIN_BREAK = b.stop_pins[wheel], b.brake_pins[wheel]
        self.PIN_DIRECTION, self.PIN_CONTROL = b.dir_pins[wheel], b.pwm_pins[wheel]
        self.PIN_SPEED = b.speed_pins[wheel]
        self.motion = STOP
        self.referenceSpeed = 0.0  # RPM
        self.actualSpeed = 0.0  # RPM, last sample
        self.drivenSpeed = 0.0  # RPM, last commanded
        self.sensed = False
        self.controlled = False

    def computeDutyFromRPM(self, rpm: float) -> float:
        """Listing 4.9: duty = rpm / MAX_VEL."""
        return rpm / self.p.max_vel_rpm

    @staticmethod
    def computeVolt(duty: float) -> float:
        """Listing 4.9: analogWrite value = duty * 255 (truncated by analogWrite)."""
        return duty * 255.0

    def stop(self) -> None:
        """Motion STOP: PWM 0 and BRAKE high (wheel held). Reconstructed."""
        self.rt.analogWrite(self.PIN_CONTROL, 0)
        self.rt.digitalWrite(self.PIN_BREAK, HIGH)

    def start(self) -> None:
        """Release BRAKE, enable the driver (STOP high). Reconstructed."""
        self.rt.digitalWrite(self.PIN_BREAK, LOW)
        self.rt.digitalWrite(self.PIN_STOP, HIGH)

    def freeSpin(self) -> None:
        """Motion +-1 at speed 0: PWM 0, BRAKE low, STOP low (coast). Reconstructed."""
        self.rt.analogWrite(self.PIN_CONTROL, 0)
        self.rt.digitalWrite(self.PIN_BREAK, LOW)
        self.rt.digitalWrite(self.PIN_STOP, LOW)

    def forward(self) -> None:
        self.rt.digitalWrite(self.PIN_DIRECTION, HIGH)

    def backward(self) -> None:
        self.rt.digitalWrite(self.PIN_DIRECTION, LOW)

    def changeDirection(self) -> None:
        """Invert the motion and the DIR pin."""
        self.motion = -self.motion
        self.forward() if self.motion == FORWARD else self.backward()

    def drive(self, drivSpeed: float) -> MainTask:
        """Listing 4.10: start, set DIR from ``motion``, ramp from actualSpeed."""
        self.start()
        if self.motion == FORWARD:
            self.forward()
        elif self.motion == BACKWARD:
            self.backward()
        else:
            return
        self.drivenSpeed = drivSpeed
        yield from self.acceleration(self.actualSpeed, self.drivenSpeed)

    def driveNoAcc(self, drivSpeed: float) -> None:
        """Listing 4.10: write the duty of ``drivSpeed`` at once."""
        self.drivenSpeed = drivSpeed
        self.rt.analogWrite(self.PIN_CONTROL, self.computeVolt(self.computeDutyFromRPM(drivSpeed)))

    def acceleration(self, initialSpeed: float, finalSpeed: float) -> MainTask:
        """Listing 4.10: 10 analogWrite steps, each followed by delay(delayTime)."""
        p = self.p
        initialDuty = self.computeDutyFromRPM(initialSpeed)
        finalDuty = self.computeDutyFromRPM(finalSpeed)
        deltaDuty = (finalDuty - initialDuty) / p.ramp_steps
        delayTime = 0
        if abs(deltaDuty) >= p.threshold_high_acc:
            delayTime = p.delay_high_ms
        elif abs(deltaDuty) >= p.threshold_medium_acc:
            delayTime = p.delay_medium_ms
        elif abs(deltaDuty) >= p.threshold_small_acc:
            delayTime = p.delay_small_ms
        test = deltaDuty if p.quirk_signed_ramp_test else abs(deltaDuty)
        if test >= p.threshold_small_acc:
            for i in range(1, p.ramp_steps + 1):
                self.rt.analogWrite(self.PIN_CONTROL, self.computeVolt(initialDuty + deltaDuty * i))
                yield delayTime
        else:
            self.driveNoAcc(finalSpeed)


class FaithfulFirmware:
    """The thesis firmware on an emulated Arduino Mega (``motor_control.ino``).

    Parameters
    ----------
    clock : VirtualClock
        Shared clock.
    publish : callable
        ``publish(topic, rpm)``; ``wheel0_Vel``/``wheel1_Vel``, RPM >= 0.
    edges_per_rev : int
        SC changes per wheel revolution (``wheel.sc_edges_per_rev``: 90, the listing's count).
    params : FaithfulParams
        Thesis constants and quirk switches.
    """

    def __init__(
        self,
        clock: VirtualClock,
        publish: Publish,
        edges_per_rev: int,
        params: FaithfulParams | None = None,
    ):
        self.p = p = params or FaithfulParams()
        self.edges_per_rev = int(edges_per_rev)
        self.clock, self._publish = clock, publish
        self.rt = ArduinoRuntime(clock, p.board)
        self.pins = self.rt.pins
        self.motors = (Motor(self.rt, p, 0), Motor(self.rt, p, 1))
        self.counter = [0, 0]
        self.lastRead = [0, 0]
        self.actualRead = [0, 0]
        self.reader = [False, False]
        self.last_time = [0, 0]
        self.last_error = [0.0, 0.0]
        self.total_error = [0.0, 0.0]
        self.previousSetPoint = [0.0, 0.0]
        self._isr = (lambda: self.speedChangeInt(0), lambda: self.speedChangeInt(1))
        self.sample_edges = (
            self.edges_per_rev if p.quirk_first_sample_after_full_rev else p.short_sample_edges
        )

    # -- Firmware protocol ---------------------------------------------------------
    def connect(self, bus, link) -> bool:
        """No UART of its own: the loop bridges wheel_Command and the published speeds."""
        return False

    def start(self) -> None:
        """setup(): wheels braked, Timer1 every 0.2 s calling PICallBack."""
        for m in self.motors:
            m.stop()
            m.rt.digitalWrite(m.PIN_STOP, HIGH)
            m.forward()
        self.rt.timer_initialize(self.p.timer_period_us, self.PICallBack)

    def on_wheel_command(self, data: Sequence[float]) -> None:
        """rosserial delivered wheel_Command: handled by loop()'s spinOnce()."""
        values = tuple(float(x) for x in data)
        self.rt.post_main(lambda: self.wheelCommandCallback(values))

    def on_sc_edge(self, wheel: int) -> None:
        """SC change on pin 2 (wheel 0) or 3 (wheel 1)."""
        self.rt.external_edge(wheel)

    # -- main context ----------------------------------------------------------------
    def wheelCommandCallback(self, data: Sequence[float]) -> MainTask:
        """Subscriber of wheel_Command ``[motionL, speedL, motionR, speedR]``. Reconstructed."""
        for i, m in enumerate(self.motors):
            motion, speed = int(data[2 * i]), data[2 * i + 1]
            m.motion = motion
            if motion == STOP:
                m.referenceSpeed = 0.0
                m.stop()
            elif speed == 0:
                m.referenceSpeed = 0.0
                m.freeSpin()
            else:
                m.referenceSpeed = speed
                yield from m.drive(speed)

    # -- Timer1 ISR --------------------------------------------------------------------
    def PICallBack(self) -> None:
        """Per wheel: not sensed -> attach its SC interrupt; sensed -> PI_Control. Reconstructed."""
        for i, m in enumerate(self.motors):
            if not m.sensed:
                self.rt.attachInterrupt(self.rt.digitalPinToInterrupt(m.PIN_SPEED), self._isr[i])
            elif not m.controlled:
                self.PI_Control(m.referenceSpeed, m.actualSpeed, i)

    def PI_Control(self, setPoint: float, sensedOutput: float, index: int) -> None:
        """Listing 4.11."""
        p, rt, m = self.p, self.rt, self.motors[index]
        rt.noInterrupts()
        m.sensed = False
        if setPoint != 0:
            current_time = rt.millis()
            elapsed_ms = (current_time - self.last_time[index]) & 0xFFFFFFFF
            if p.quirk_int_ms_delta_vs_T:
                due = _int16(elapsed_ms) >= p.t_s  # int ms against T = 0.2
            else:
                due = elapsed_ms >= p.t_s * 1000.0
            if due:
                if setPoint != self.previousSetPoint[index]:
                    self.total_error[index] = 0.0
                    self.previousSetPoint[index] = setPoint
                error = setPoint - sensedOutput
                if abs(error) <= p.threshold_control_rpm:
                    if not p.quirk_pi_early_return_keeps_interrupts_off:
                        rt.interrupts()
                    return
                total = self.total_error[index] + error
                total = min(max(total, p.min_control_rpm), p.max_control_rpm)
                self.total_error[index] = total
                delta_error = error - self.last_error[index]
                bias = setPoint / p.bias_divisor
                controlSpeed = (
                    setPoint
                    + (p.kp * error + (p.ki * p.t_s) * total + (p.kd / p.t_s) * delta_error)
                    - bias
                )
                controlSpeed = min(max(controlSpeed, p.min_control_rpm), p.max_control_rpm)
                self.last_error[index] = error
                self.last_time[index] = current_time
                m.driveNoAcc(controlSpeed)
            m.controlled = True
            rt.interrupts()
        elif not p.quirk_pi_early_return_keeps_interrupts_off:
            rt.interrupts()

    # -- INT4/INT5 ISR -----------------------------------------------------------------
    def speedChangeInt(self, index: int) -> None:
        """Listing 4.12: time ``sample_edges`` SC changes with micros(), publish, detach."""
        rt, m = self.rt, self.motors[index]
        if m.sensed:
            return
        if self.counter[index] == 0:
            self.lastRead[index] = rt.micros()
            self.counter[index] += 1
            self.reader[index] = True
        elif self.counter[index] == self.sample_edges:
            rt.detachInterrupt(rt.digitalPinToInterrupt(m.PIN_SPEED))
            rt.noInterrupts()
            self.actualRead[index] = (rt.micros() - self.lastRead[index]) & 0xFFFFFFFF
            self.lastRead[index] = rt.micros()
            m.actualSpeed = self.computeSpeedFromSignal(self.actualRead[index])
            self._publish(f"wheel{index}_Vel", m.actualSpeed)
            self.counter[index] = 0
            self.reader[index] = False
            m.sensed = True
            m.controlled = False
            rt.interrupts()
        else:
            self.counter[index] += 1

    def computeSpeedFromSignal(self, val: float) -> float:
        """RPM from the micros() elapsed over one sample. Reconstructed: 60e6 / val per rev."""
        if val <= 0:
            return 0.0
        return 60e6 * (self.sample_edges / self.edges_per_rev) / val
