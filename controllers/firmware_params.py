"""The firmware interface seen by the simulation loop and the firmwares' parameters.

:class:`Firmware` is what the loop calls; ``BoardParams`` is the Arduino Mega's
wiring, ``FaithfulParams`` the thesis listings' constants and quirk switches,
``ImprovedParams`` the improved firmware's and ``AvrParams`` the emulated board's.
The factory that builds a firmware from its kind is :mod:`~amr_twin.controllers.firmware`.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable, Protocol, Sequence

from amr_twin.base.pins import DriverPins

Publish = Callable[[str, float], None]
"""``publish(topic, value)``: a std_msgs/Float64 leaving the Arduino over rosserial."""


class Firmware(Protocol):
    """What the simulation loop calls; see the module docstring of each port."""

    pins: tuple[DriverPins, DriverPins]

    def connect(self, bus, link) -> bool:
        """Attach to the PC side: True if the firmware speaks rosserial on its own (emulated) UART
        over ``link`` with ``bus`` (the loop then bridges nothing), False if the loop should bridge
        ``wheel_Command`` to :meth:`on_wheel_command` and the published speeds itself."""

    def start(self) -> None:
        """setup(): initial pin levels, the timer scheduled on the clock."""

    def on_wheel_command(self, data: Sequence[float]) -> None:
        """A wheel_Command ``[motionL, speedL, motionR, speedR]`` arrived at ``clock.now_us``."""

    def on_sc_edge(self, wheel: int) -> None:
        """An SC state change of ``wheel`` (0 left, 1 right) at ``clock.now_us``."""


@dataclass(frozen=True)
class BoardParams:
    """Arduino Mega 2560 wiring and hardware behaviour."""

    speed_pins: tuple[int, int] = (2, 3)  # SC inputs, left/right; §3.2.3 "digital pins 2 and 3"
    pwm_pins: tuple[int, int] = (
        6,
        7,
    )  # PWM outputs; assumed (thesis silent; avoids Timer1 pins 11/12)
    dir_pins: tuple[int, int] = (26, 27)  # DIR outputs; assumed
    brake_pins: tuple[int, int] = (24, 25)  # BRAKE outputs; assumed
    stop_pins: tuple[int, int] = (22, 23)  # STOP outputs; assumed
    latch_int_flag_while_detached: bool = (
        False  # True: AVR sets INTFn on an edge even when EIMSK masks it,
    )
    # and attachInterrupt() does not clear it: a stale edge fires on attach (ArduinoCore-avr #244)
    record_pin_log: bool = False  # keep (t_us, wheel, counts) of every analogWrite, for tests


@dataclass(frozen=True)
class FaithfulParams:
    """Constants of the thesis firmware and its quirk switches (all True = as printed)."""

    max_vel_rpm: float = 1054.0  # MAX_VEL, RPM at duty 1; listing 4.7
    timer_period_us: int = 200_000  # PICallBack timer; §3.2.3 "every 0.2 seconds"
    kp: float = 0.001  # proportional gain, duty-free RPM/RPM; §4 listing 4.11 text
    ki: float = 0.15  # integral gain, 1/s; listing 4.11 text
    kd: float = 0.0  # derivative gain, s; unused in the thesis
    t_s: float = 0.2  # T, s; not printed: only 0.2 s makes ki*T sensible (robot-facts.md)
    bias_divisor: float = 10.0  # bias = setPoint/10; listing 4.11 line 27
    threshold_control_rpm: float = 4.0  # THRESHOLD_CONTROL, RPM; listing 4.8
    min_control_rpm: float = 0.0  # min_control, RPM; not printed: no reverse drive through PWM
    max_control_rpm: float = 1054.0  # max_control, RPM; not printed: duty 1 = MAX_VEL
    threshold_small_acc: float = 0.005  # THRESHOLD_SMALL_ACC, duty per step; listing 4.8
    threshold_medium_acc: float = 0.009  # THRESHOLD_MEDIUM_ACC, duty per step; listing 4.8
    threshold_high_acc: float = 0.011  # THRESHOLD_HIGH_ACC, duty per step; listing 4.8
    delay_small_ms: int = 50  # DELAY_SMALL_ACC, ms; listing 4.8
    delay_medium_ms: int = 150  # DELAY_MEDIUM_ACC, ms; listing 4.8
    delay_high_ms: int = 250  # DELAY_HIGH_ACC, ms; listing 4.8
    ramp_steps: int = 10  # analogWrite steps of a ramp; listing 4.10
    quirk_signed_ramp_test: bool = True  # `deltaDuty >= THRESHOLD_SMALL_ACC`: decelerations jump
    quirk_pi_early_return_keeps_interrupts_off: bool = True  # PI_Control returns w/o interrupts()
    quirk_int_ms_delta_vs_T: bool = True  # 16-bit int ms delta compared with T = 0.2 (s)
    quirk_first_sample_after_full_rev: bool = (
        True  # a revolution of changes per sample (90, §2.2.1)
    )
    short_sample_edges: int = 18  # SC changes per sample when the quirk above is off (1/5 rev)
    board: BoardParams = field(default_factory=BoardParams)


@dataclass(frozen=True)
class ImprovedParams:
    """Improved firmware: per-edge speed, fixed-rate PI with anti-windup, two-way ramp."""

    max_vel_rpm: float = 1054.0  # RPM at duty 1; listing 4.7
    window_edges: int = 18  # max SC intervals in the sliding period window (1/5 rev)
    window_us: int = 100_000  # max age of the window's oldest edge, us
    zero_speed_timeout_us: int = 150_000  # no edge for this long -> speed 0, us
    pi_period_us: int = 20_000  # PI tick (50 Hz), us
    publish_every_ticks: int = 5  # wheelN_Vel every 5 PI ticks (10 Hz)
    publish_mean: bool = (
        True  # wheelN_Vel is the mean speed since the previous sample (edges counted);
    )
    # False: the PI's sliding-window estimate at that instant (the former default; the odometry then
    # loses about an edge per wheel at each start and stop, docs/explanation/umbmark.md)
    extrapolate_above_rpm: float = (
        15.0  # the mean counts the part of an edge rolled since the last edge
    )
    # at this per-edge speed or more: braked from 15 RPM a wheel of the twin rolls 43 mm (5 edges)
    # on, so the edge is sure to come; below, whole edges only (a sample then resolves one edge, 6.7
    # RPM at 10 Hz)
    kp: float = 0.5  # proportional gain, RPM of command per RPM of error
    ki: float = 3.0  # integral gain, RPM of command per RPM*s of error, 1/s
    feedforward_gain: float = 0.9  # open-loop command = gain * reference (listing 4.11's bias)
    min_control_rpm: float = 0.0  # command lower bound, RPM
    max_control_rpm: float = 1054.0  # command upper bound (duty 1), RPM
    ramp_rate_rpm_per_s: float = 150.0  # slew limit of the reference, up and down, RPM/s
    integral_band_rpm: float = 8.0  # integrate only when |error| <= band and the ramp is done, RPM
    dither_pwm: bool = True  # sigma-delta on the 8-bit PWM: the mean duty is not quantised
    board: BoardParams = field(default_factory=BoardParams)


@dataclass(frozen=True)
class AvrParams:
    """The firmware as a sketch on an emulated ATmega2560 (controllers/avr.py)."""

    sketch_dir: str | None = (
        None  # sketch folder (FOLDER/FOLDER.ino); None: controllers/arduino/motor_control
    )
    idle_sleep: bool = (
        True  # rosserial spinOnce() sleeps until the next interrupt when it finds nothing
    )
    # to read (ros_lib/ArduinoHardware.h); False: busy loop as rosserial_arduino (same results, ~3x
    # slower)
    sync_period_us: int = 1000  # the board is brought up to the loop's time at least this often, us
    board: BoardParams = field(default_factory=BoardParams)  # pins the sketch must use (its wiring)
    serial_pty: str | None = (
        None  # serve USART0 on a pseudo-terminal linked at this path, paced to wall
    )
    # time, for a rosserial host (controllers/avr_serial_port.py); None: the twin's own PC side is
    # the host
