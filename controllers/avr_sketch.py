"""A sketch on the emulated ATmega2560 before the twin runs it: the defines it is built with
(:func:`sketch_defines`), the baud it set on USART0 (:func:`byte_cycles`) and the rosserial topics
it answers (:func:`topic_table`, asked as rosserial_python asks)."""

from __future__ import annotations

from functools import lru_cache

from amr_twin.controllers.avr_board import AvrBoard
from amr_twin.controllers.avr_build import SketchError
from amr_twin.controllers.firmware_params import AvrParams
from amr_twin.ros.rosserial_frame import (
    ID_PUBLISHER,
    ID_SUBSCRIBER,
    FrameParser,
    TopicInfo,
    topic_request,
)

CYCLES_PER_US = 16
UBRR0L, UBRR0H, UCSR0A = 0xC4, 0xC5, 0xC0
"""USART0 baud registers (data-space addresses)."""

KNOWN_TYPES = ("std_msgs/Float64", "std_msgs/Float64MultiArray")
CONFIGURED_AT_START = "AMR_TWIN_ROS_CONFIGURED_AT_START"
"""ros_lib define of the twin's own runs: the board starts configured (the twin is the host)."""


def sketch_defines(params: AvrParams) -> tuple[str, ...]:
    """The preprocessor names the sketch of ``params`` is built with."""
    defines = () if params.idle_sleep else ("AMR_TWIN_ROS_BUSY_SPIN",)
    return defines if params.serial_pty is not None else defines + (CONFIGURED_AT_START,)


def byte_cycles(board: AvrBoard) -> int:
    """CPU cycles of one 8N1 byte at the baud the firmware set on USART0."""
    ubrr = board.peek(UBRR0L) | (board.peek(UBRR0H) & 0x0F) << 8
    u2x = board.peek(UCSR0A) & 0x02
    return 10 * (ubrr + 1) * (8 if u2x else 16)


@lru_cache(maxsize=16)
def topic_table(elf: str) -> tuple[tuple[TopicInfo, ...], tuple[TopicInfo, ...]]:
    """``(publishers, subscribers)`` of a sketch, from its answer to a topic request.

    The ELF runs on its own board for up to 0.5 s: 5 ms to set up, then the request frame.
    """
    board = AvrBoard(elf, [], {})
    try:
        start = 5_000 * CYCLES_PER_US
        board.run_to(start)
        board.queue_rx(start, topic_request(), byte_cycles(board))
        parser, pubs, subs = FrameParser(), [], []
        for ms in range(10, 500, 5):
            board.run_to(ms * 1000 * CYCLES_PER_US)
            for f in parser.feed(bytes(b for _, b in board.take_tx())):
                if f.topic_id in (ID_PUBLISHER, ID_SUBSCRIBER):
                    (pubs if f.topic_id == ID_PUBLISHER else subs).append(
                        TopicInfo.deserialize(f.message)
                    )
            if (pubs or subs) and parser.pending[0] == 0 and ms >= 50:
                break
    finally:
        board.close()
    if not pubs and not subs:
        raise SketchError(
            f"{elf}: the sketch did not answer rosserial's topic request within 0.5 s "
            "(does setup() call node.initNode() and loop() node.spinOnce()?)"
        )
    for info in pubs + subs:
        if info.message_type not in KNOWN_TYPES:
            raise SketchError(
                f"topic {info.topic_name}: type {info.message_type} is not carried by the "
                f"twin's rosserial bridge ({', '.join(KNOWN_TYPES)})"
            )
    return tuple(pubs), tuple(subs)
