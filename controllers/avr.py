"""The firmware as the board runs it: an Arduino sketch compiled with avr-gcc on an emulated
ATmega2560.

Reasons and measurements: docs/explanation/firmware.md#amr_twincontrollersavr."""

from __future__ import annotations

import struct
from collections import deque
from typing import Sequence

from amr_twin.base.clock import VirtualClock
from amr_twin.ros.messages import Float64, Float64MultiArray
from amr_twin.base.pins import DriverPins
from amr_twin.ros.rosserial import ARDUINO_TO_PC, PC_TO_ARDUINO
from amr_twin.ros.rosserial_frame import (
    ID_PUBLISHER,
    ID_TIME,
    FrameParser,
    TopicInfo,
    deserialize_float64,
    frame,
    serialize_float64,
    serialize_float64_multiarray,
)

from amr_twin.controllers.avr_board import AvrBoard, BoardError, symbol_address
from amr_twin.controllers.avr_build import DEFAULT_SKETCH, SketchError, build_sketch
from amr_twin.controllers.avr_sketch import CYCLES_PER_US, byte_cycles, sketch_defines, topic_table
from amr_twin.controllers.firmware_params import AvrParams, Publish


class AvrFirmware:
    """The sketch of ``params.sketch_dir`` on an emulated Mega; see the module docstring.

    Parameters
    ----------
    clock : VirtualClock
    publish : callable
        ``publish(topic, value)`` for the board's Float64 topics when no bus is connected
        (:meth:`connect`), called at the frame's arrival.
    params : AvrParams
    """

    def __init__(self, clock: VirtualClock, publish: Publish, params: AvrParams | None = None):
        self.p = p = params or AvrParams()
        b = p.board
        if b.latch_int_flag_while_detached or b.record_pin_log:
            raise ValueError(
                "AvrParams.board: latch_int_flag_while_detached and record_pin_log belong to the "
                "Python ports' board; simavr decides the first, and the emulated board keeps no "
                "pin log"
            )
        sketch = DEFAULT_SKETCH if p.sketch_dir is None else p.sketch_dir
        self.elf = str(build_sketch(sketch, sketch_defines(p)))
        publishers, subscribers = topic_table(self.elf)
        self.publishers = {info.topic_id: info for info in publishers}
        self.subscribers = {info.topic_name: info for info in subscribers}
        outputs = [
            pin
            for w in range(2)
            for pin in (b.pwm_pins[w], b.dir_pins[w], b.brake_pins[w], b.stop_pins[w])
        ]
        self.board = AvrBoard(self.elf, outputs, {b.speed_pins[0]: 0, b.speed_pins[1]: 0})
        if not self.board.run_to_symbol(symbol_address(self.elf, "loop"), 16_000_000):
            raise SketchError(f"{sketch}: setup() did not return within 1 s")
        self.lead_cycles = self.board.cycle
        """CPU cycles from reset to the first loop(): the board's cycle at t = 0."""
        self.clock, self._publish = clock, publish
        self.pins = (DriverPins(), DriverPins())
        self._speed_pins = b.speed_pins
        self._key = -1
        self._parser = FrameParser()
        self._wire_end: list[int] = []  # end cycle of each received board byte, by stream index
        self._wire_base = 0  # stream index of _wire_end[0]
        self._tx_free = 0  # cycle at which the board's TX wire is free
        self._rx_free = 0  # cycle at which the PC -> board wire is free
        self._bus = self._link = None
        self._extra_sync: int | None = None
        self.frames_dropped = 0
        """Frames from the board that failed their checksum (none expected)."""
        self.time_requests = 0
        """Time requests the board sent (rosserial's time sync; the host answers each)."""
        self.negotiations = 0
        """Topic negotiations the board answered (one per topic request of a host)."""
        self.serial = self.pacer = None
        self._serial_out: deque[tuple[int, int]] = (
            deque()
        )  # (cycle its last bit leaves the wire, byte)
        if p.serial_pty is not None:
            from amr_twin.controllers.avr_serial_port import PtySerialPort, WallPacer

            self.serial, self.pacer = PtySerialPort(p.serial_pty), WallPacer()

    # -- wiring into the twin ---------------------------------------------------------
    def connect(self, bus, link) -> bool:
        """Carry the sketch's topics between ``bus`` and the UART, with ``link``'s latency and loss
        (True: it speaks rosserial itself,
        :meth:`amr_twin.controllers.firmware_params.Firmware.connect`)."""
        self._bus, self._link = bus, link
        if self.serial is None:  # else the board's serial port is the host's
            for name, info in self.subscribers.items():
                bus.subscribe(name, lambda msg, info=info: self._send(info, msg))
        return True

    # -- Firmware protocol --------------------------------------------------------------
    def start(self) -> None:
        """Power up: run the board to now (setup() runs in its first microseconds) and keep it in
        step."""
        self._sync()
        self.clock.schedule_in(self.p.sync_period_us, self._tick)

    def on_wheel_command(self, data: Sequence[float]) -> None:
        """A wheel_Command published now: its frame starts on the board's RX wire now."""
        info = self.subscribers.get("wheel_Command")
        if info is None:
            raise SketchError("the sketch does not subscribe to wheel_Command")
        self._send(info, Float64MultiArray(data=[float(x) for x in data]))

    def on_sc_edge(self, wheel: int) -> None:
        """An SC change of ``wheel`` now: toggle its pin at this microsecond."""
        self.board.queue_edge(
            self.clock.now_us * CYCLES_PER_US + self.lead_cycles, self._speed_pins[wheel]
        )

    # -- board in step with the clock ---------------------------------------------------
    def _tick(self) -> None:
        self.clock.schedule_in(self.p.sync_period_us, self._tick)
        self._sync()
        if self.serial is not None:
            self._serve()

    def _serve(self) -> None:
        """Pseudo-terminal: pace to the wall clock, take the host's bytes, send the board's that
        left the wire."""
        now = self.clock.now_us
        self.pacer.sleep_until(now)
        data = self.serial.read()
        if data:
            self._queue_rx(now, data)
        cycle, out = now * CYCLES_PER_US + self.lead_cycles, self._serial_out
        if out and out[0][0] <= cycle:
            ready = bytearray()
            while out and out[0][0] <= cycle:
                ready.append(out.popleft()[1])
            self.serial.write(bytes(ready))

    def _sync(self) -> None:
        now = self.clock.now_us
        try:
            self.board.run_to(now * CYCLES_PER_US + self.lead_cycles)
        except BoardError as exc:
            raise BoardError(f"{exc} (sketch {self.p.sketch_dir or DEFAULT_SKETCH})") from None
        self._sync_pins()
        tx = self.board.take_tx()
        if tx:
            self._receive(tx)

    def _sync_pins(self) -> None:
        """Read the driver pins off the board (PWM: OCR or port; DIR, BRAKE, STOP: port bits)."""
        key = self.board.outputs()
        if key != self._key:
            self._key = key
            for w, pins in enumerate(self.pins):
                v = key >> (32 * w)
                pins.pwm_counts = v & 0xFF
                pins.dir_level = 1 if v >> 8 & 0xFF else 0
                pins.brake_level = 1 if v >> 16 & 0xFF else 0
                pins.stop_level = 1 if v >> 24 & 0xFF else 0

    def _receive(self, tx: list[tuple[int, int]]) -> None:
        """Board bytes written to UDR0: their time on the wire, then the frames they complete."""
        per_byte = byte_cycles(self.board)
        for cycle, byte in tx:
            self._tx_free = max(cycle, self._tx_free) + per_byte
            self._wire_end.append(self._tx_free)
            if self.serial is not None:
                self._serial_out.append((self._tx_free, byte))
        for f in self._parser.feed(bytes(b for _, b in tx)):
            arrival = -(
                -(self._wire_end[f.last - self._wire_base] - self.lead_cycles) // CYCLES_PER_US
            )
            self._deliver(f.topic_id, f.message, arrival)
        self.frames_dropped = self._parser.dropped
        got, total = self._parser.pending
        keep = len(self._wire_end) - got
        self._wire_base += keep
        del self._wire_end[:keep]
        if total is not None:  # a frame is on its way: be there when its last byte arrives
            end = self._tx_free + (total - got) * per_byte
            self._schedule_sync(-(-(end - self.lead_cycles) // CYCLES_PER_US))

    def _schedule_sync(self, t_us: int) -> None:
        if t_us <= self.clock.now_us or (self._extra_sync is not None and self._extra_sync == t_us):
            return
        self._extra_sync = t_us
        self.clock.schedule(t_us, self._sync)

    def _deliver(self, topic_id: int, message: bytes, arrival_us: int) -> None:
        if (
            topic_id == ID_PUBLISHER
        ):  # the board answers a topic request: its first publisher opens the answer
            if self.publishers and TopicInfo.deserialize(message).topic_id == min(self.publishers):
                self.negotiations += 1
            return
        if topic_id == ID_TIME:
            self.time_requests += 1
            if self.serial is None:  # the twin is the host: answer with the simulated time
                self.clock.schedule(max(arrival_us, self.clock.now_us), self._answer_time)
            return
        info = self.publishers.get(topic_id)
        if info is None or info.message_type != "std_msgs/Float64":
            return
        value = deserialize_float64(message)
        link = self._link
        if link is not None:
            if link.draw_loss(ARDUINO_TO_PC, 8 + len(message)):
                return
            arrival_us += link.extra_latency_us
        at = max(arrival_us, self.clock.now_us)
        if self._bus is not None:
            bus, topic = self._bus, info.topic_name
            self.clock.schedule(at, lambda: bus.publish(topic, Float64(data=value)))
        else:
            publish, topic = self._publish, info.topic_name
            self.clock.schedule(at, lambda: publish(topic, value))

    def _answer_time(self) -> None:
        """The host's answer to a time request: std_msgs/Time of the simulated clock, now."""
        now = self.clock.now_us
        self._send_frame(
            frame(ID_TIME, struct.pack("<II", now // 1_000_000, now % 1_000_000 * 1000))
        )

    def _send(self, info: TopicInfo, msg) -> None:
        """Put ``msg`` on the PC -> board wire as a rosserial frame on the sketch's topic id."""
        if info.message_type == "std_msgs/Float64MultiArray":
            payload = serialize_float64_multiarray([float(x) for x in msg.data])
        else:
            payload = serialize_float64(float(msg.data))
        self._send_frame(frame(info.topic_id, payload))

    def _send_frame(self, data: bytes) -> None:
        """A frame from the twin's PC side on the PC -> board wire, from now (plus the link's
        latency, or lost)."""
        start_us = self.clock.now_us
        if self._link is not None:
            start_us += self._link.extra_latency_us
            if self._link.draw_loss(PC_TO_ARDUINO, len(data)):
                data = data[:-1] + bytes(
                    ((data[-1] + 1) & 0xFF,)
                )  # the checksum fails on the board
        self._queue_rx(start_us, data)

    def _queue_rx(self, start_us: int, data: bytes) -> None:
        """Bytes entering the board's receiver from ``start_us`` on, behind those already queued."""
        per_byte = byte_cycles(self.board)
        start = max(start_us * CYCLES_PER_US + self.lead_cycles, self._rx_free, self.board.cycle)
        self.board.queue_rx(start, data, per_byte)
        self._rx_free = start + len(data) * per_byte

    def close(self) -> None:
        """Free the emulator (and the pseudo-terminal)."""
        if self.serial is not None:
            self.serial.close()
        self.board.close()
