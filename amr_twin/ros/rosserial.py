"""The rosserial link between the mini PC and the Arduino Mega (launch file, listing 4.1).

Reasons and measurements: docs/how-to/ros1.md#amr_twinrosrosserial."""

from __future__ import annotations

import copy
import random
from typing import Any, Callable

from amr_twin.ros.messages import Float64, Float64MultiArray, MultiArrayLayout
from amr_twin.base.clock import VirtualClock

FRAME_OVERHEAD_BYTES = 8
"""rosserial framing bytes added to each serialised message."""

BITS_PER_BYTE = 10
"""UART 8N1: start bit + 8 data bits + stop bit."""

PC_TO_ARDUINO = "pc_to_arduino"
"""Direction of ``wheel_Command``."""

ARDUINO_TO_PC = "arduino_to_pc"
"""Direction of ``wheel0_Vel`` and ``wheel1_Vel``."""

Deliver = Callable[[str, Any], None]


def snapshot(msg: Any) -> Any:
    """The values ``msg`` holds now, as the far end of the wire gets them (a message the sender may
    reuse).

    The link's two messages are rebuilt from their fields (``std_msgs/Float64``, and
    ``Float64MultiArray`` with no layout dimensions, as ``wheel_Command`` is sent): a
    tenth of ``copy.deepcopy``'s time on the 20 Hz wheel commands of a navigating twin;
    any other message is deep-copied.
    """
    kind = type(msg)
    if kind is Float64:
        return Float64(msg.data)
    if kind is Float64MultiArray and not msg.layout.dim:
        return Float64MultiArray(
            MultiArrayLayout(data_offset=msg.layout.data_offset), list(msg.data)
        )
    return copy.deepcopy(msg)


def frame_bytes(msg: Any) -> int:
    """Bytes of the rosserial frame carrying ``msg``."""
    return FRAME_OVERHEAD_BYTES + msg.serialized_size()


def frame_time_us(n_bytes: int, baud: int) -> int:
    """Microseconds ``n_bytes`` occupy a UART at ``baud`` bit/s (rounded up)."""
    bits = n_bytes * BITS_PER_BYTE
    return -(-bits * 1_000_000 // int(baud))


class RosserialLink:
    """Two serial wires (one per direction) carrying rosserial frames in sim time.

    Parameters
    ----------
    clock : VirtualClock
        Shared clock; each arrival is an event on it.
    baud : int
        UART speed, bit/s (115200 in the launch file).
    extra_latency_us : int
        Added after the last byte of each frame, microseconds.
    loss_prob : float
        Probability in [0, 1] that a frame is lost.
    seed : int
        Seed of the loss draws.
    """

    def __init__(
        self,
        clock: VirtualClock,
        baud: int = 115200,
        extra_latency_us: int = 0,
        loss_prob: float = 0.0,
        seed: int = 0,
    ):
        if baud <= 0:
            raise ValueError(f"baud must be positive, got {baud}")
        if not 0.0 <= loss_prob <= 1.0:
            raise ValueError(f"loss_prob must be in [0, 1], got {loss_prob}")
        if extra_latency_us < 0:
            raise ValueError(f"extra_latency_us must be >= 0, got {extra_latency_us}")
        self.clock = clock
        self.baud = int(baud)
        self.extra_latency_us = int(extra_latency_us)
        self.loss_prob = float(loss_prob)
        self._rng = random.Random(seed)
        self._busy_until_us = {PC_TO_ARDUINO: 0, ARDUINO_TO_PC: 0}
        self.frames_sent = {PC_TO_ARDUINO: 0, ARDUINO_TO_PC: 0}
        self.frames_lost = {PC_TO_ARDUINO: 0, ARDUINO_TO_PC: 0}
        self.bytes_sent = {PC_TO_ARDUINO: 0, ARDUINO_TO_PC: 0}

    def busy_until_us(self, direction: str) -> int:
        """Time at which the wire of ``direction`` becomes free, microseconds."""
        return max(self._busy_until_us[direction], self.clock.now_us)

    def draw_loss(self, direction: str, n_bytes: int) -> bool:
        """Account a frame of ``n_bytes`` that another model times (an emulated UART); True if lost.

        Same counters and seeded draws as :meth:`send`.
        """
        self.frames_sent[direction] += 1
        self.bytes_sent[direction] += n_bytes
        if self.loss_prob > 0.0 and self._rng.random() < self.loss_prob:
            self.frames_lost[direction] += 1
            return True
        return False

    def send(self, direction: str, topic: str, msg: Any, deliver: Deliver) -> int | None:
        """Queue ``msg`` on the wire of ``direction``; call ``deliver(topic, msg)`` on arrival.

        ``deliver`` can be :meth:`amr_twin.ros.bus.Bus.publish` (PC side) or a
        firmware's subscriber callback wrapper.

        Returns
        -------
        int or None
            Arrival time in microseconds, or ``None`` if the frame is lost.
        """
        if direction not in self._busy_until_us:
            raise ValueError(
                f"unknown direction {direction!r}; use {PC_TO_ARDUINO!r} or {ARDUINO_TO_PC!r}"
            )
        n_bytes = frame_bytes(msg)
        start_us = self.busy_until_us(direction)
        end_us = start_us + frame_time_us(n_bytes, self.baud)
        self._busy_until_us[direction] = end_us
        self.frames_sent[direction] += 1
        self.bytes_sent[direction] += n_bytes
        if self.loss_prob > 0.0 and self._rng.random() < self.loss_prob:
            self.frames_lost[direction] += 1
            return None
        arrival_us = end_us + self.extra_latency_us
        sent = snapshot(msg)  # the receiver gets the values as serialised now
        self.clock.schedule(arrival_us, lambda: deliver(topic, sent))
        return arrival_us
