"""Emulated Arduino Mega 2560 runtime on the shared virtual clock.

What a sketch sees: ``micros()``/``millis()`` (from :class:`VirtualClock`), a
periodic timer interrupt (TimerOne-like), ``attachInterrupt``/``detachInterrupt``
for the external interrupts on the SC pins, ``noInterrupts()``/``interrupts()``,
``delay()`` in main context, 8-bit ``analogWrite`` and ``digitalWrite`` onto the
:class:`~amr_twin.base.pins.DriverPins` of the two drivers.

Reasons and measurements: docs/explanation/firmware.md#amr_twincontrollersarduino."""

from __future__ import annotations

from collections import deque
from typing import Callable, Generator, Iterator

from amr_twin.base.clock import VirtualClock
from amr_twin.base.pins import HIGH, LOW, DriverPins

from amr_twin.controllers.firmware_params import BoardParams

MainTask = Generator[int, None, None]
"""Main-context work: yields delay() durations in milliseconds."""


class ArduinoRuntime:
    """Arduino core functions and interrupt controller for the twin.

    Parameters
    ----------
    clock : VirtualClock
        Shared clock; ``micros()`` is ``clock.micros()``.
    board : BoardParams
        Pin numbers and hardware options.
    """

    def __init__(self, clock: VirtualClock, board: BoardParams):
        self.clock = clock
        self.board = board
        self.pins = (DriverPins(), DriverPins())
        self._pin_map: dict[int, tuple[int, str]] = {}
        for wheel in range(2):
            self._pin_map[board.pwm_pins[wheel]] = (wheel, "pwm_counts")
            self._pin_map[board.dir_pins[wheel]] = (wheel, "dir_level")
            self._pin_map[board.brake_pins[wheel]] = (wheel, "brake_level")
            self._pin_map[board.stop_pins[wheel]] = (wheel, "stop_level")
        self.pin_log: list[tuple[int, int, int]] | None = [] if board.record_pin_log else None
        self.sreg_i = True
        self.isr_depth = 0
        self.isr_trace: list[tuple[int, str, int]] = []  # (t_us, source, depth) when recording
        n_ext = len(board.speed_pins)
        self._ext_isr: list[Callable[[], None] | None] = [None] * n_ext
        self._ext_enabled = [False] * n_ext
        self._ext_flag = [False] * n_ext
        self._ext_mode_set = [False] * n_ext
        self._timer_isr: Callable[[], None] | None = None
        self._timer_flag = False
        self._timer_period_us = 0
        self._main_queue: deque[Callable[[], MainTask | None]] = deque()
        self._main_task: Iterator[int] | None = None

    # -- time -------------------------------------------------------------------------
    def micros(self) -> int:
        """Microseconds since start, unsigned long (wraps at 2**32)."""
        return self.clock.micros()

    def millis(self) -> int:
        """Milliseconds since start, unsigned long (wraps at 2**32)."""
        return self.clock.millis()

    # -- pins -------------------------------------------------------------------------
    def digitalWrite(self, pin: int, level: int) -> None:
        """Set an output pin HIGH (1) or LOW (0)."""
        wheel, attr = self._pin_map[pin]
        setattr(self.pins[wheel], attr, HIGH if level else LOW)

    def analogWrite(self, pin: int, value: float) -> None:
        """8-bit PWM. ``value`` is converted to ``int`` by truncation, as C does.

        Values outside 0..255 are clamped (the firmwares never produce them).
        """
        counts = min(max(int(value), 0), 255)
        wheel, _ = self._pin_map[pin]
        self.pins[wheel].pwm_counts = counts
        if self.pin_log is not None:
            self.pin_log.append((self.clock.now_us, wheel, counts))

    # -- interrupts -------------------------------------------------------------------
    def digitalPinToInterrupt(self, pin: int) -> int:
        """Interrupt number of an SC pin (0 for pin 2, 1 for pin 3)."""
        return self.board.speed_pins.index(pin)

    def noInterrupts(self) -> None:
        """CLI: hold every interrupt pending."""
        self.sreg_i = False

    def interrupts(self) -> None:
        """SEI: pending interrupts run now (nested if called inside an ISR)."""
        self.sreg_i = True
        self._service()

    def attachInterrupt(self, number: int, isr: Callable[[], None]) -> None:
        """Attach ``isr`` on CHANGE of external interrupt ``number``; a latched flag fires."""
        self._ext_isr[number] = isr
        self._ext_enabled[number] = True
        self._ext_mode_set[number] = True
        self._service()

    def detachInterrupt(self, number: int) -> None:
        """Mask external interrupt ``number`` (its flag may still latch edges)."""
        self._ext_enabled[number] = False
        self._ext_isr[number] = None

    def external_edge(self, number: int) -> None:
        """A logic change on the pin of external interrupt ``number`` at ``clock.now_us``."""
        if self._ext_enabled[number] or (
            self._ext_mode_set[number] and self.board.latch_int_flag_while_detached
        ):
            self._ext_flag[number] = True
            self._service()

    def timer_initialize(self, period_us: int, isr: Callable[[], None]) -> None:
        """Timer1.initialize(period_us); Timer1.attachInterrupt(isr): first tick one period on."""
        self._timer_period_us = int(period_us)
        self._timer_isr = isr
        self.clock.schedule_in(self._timer_period_us, self._timer_tick)

    def _timer_tick(self) -> None:
        self.clock.schedule_in(self._timer_period_us, self._timer_tick)
        self._timer_flag = True
        self._service()

    def _service(self) -> None:
        """Run pending, enabled ISRs while I = 1, highest priority first."""
        while self.sreg_i:
            for number, flag in enumerate(self._ext_flag):
                if flag and self._ext_enabled[number]:
                    self._ext_flag[number] = False
                    self._run_isr(self._ext_isr[number], f"INT{number}")
                    break
            else:
                if not self._timer_flag:
                    return
                self._timer_flag = False
                self._run_isr(self._timer_isr, "TIMER1")

    def _run_isr(self, isr: Callable[[], None] | None, source: str) -> None:
        self.sreg_i = False
        self.isr_depth += 1
        if self.pin_log is not None:
            self.isr_trace.append((self.clock.now_us, source, self.isr_depth))
        try:
            if isr is not None:
                isr()
        finally:
            self.isr_depth -= 1
            self.sreg_i = True  # RETI

    # -- main context -----------------------------------------------------------------
    @property
    def main_blocked(self) -> bool:
        """True while a main-context task sits in ``delay()``."""
        return self._main_task is not None

    def post_main(self, work: Callable[[], MainTask | None]) -> None:
        """Run ``work`` in main context now, or after the blocked task finishes."""
        self._main_queue.append(work)
        if self._main_task is None:
            self._run_main()

    def _run_main(self) -> None:
        while self._main_task is None and self._main_queue:
            task = self._main_queue.popleft()()
            if task is not None:
                self._main_task = task
                self._step_main()

    def _step_main(self) -> None:
        try:
            delay_ms = next(self._main_task)
        except StopIteration:
            self._main_task = None
            self._run_main()
            return
        self.clock.schedule_in(int(delay_ms) * 1000, self._step_main)
