"""The emulated Mega's serial port on a pseudo-terminal, spoken to by a host written here from the
rosserial protocol (no ROS needed): ros_lib's negotiation, time sync, TX_STOP, and no publishing
before configured."""

import os
import select
import struct
import time

import pytest

from amr_twin.controllers.avr_build import missing_tools
from amr_twin.controllers.firmware import AvrParams
from amr_twin.model.config import load_config
from amr_twin.ros.rosserial_frame import (
    ID_PUBLISHER,
    ID_SUBSCRIBER,
    ID_TIME,
    ID_TX_STOP,
    FrameParser,
    TopicInfo,
    frame,
    serialize_float64_multiarray,
    topic_request,
)
from amr_twin.assembly.twin import Twin, TwinOptions
from amr_twin.recording.recorder import attach_recorder, recorder_of

MISSING = missing_tools()
pytestmark = pytest.mark.skipif(MISSING is not None, reason=MISSING or "")


@pytest.fixture(scope="module")
def link(tmp_path_factory):
    path = tmp_path_factory.mktemp("pty") / "ttyACM0"
    twin = Twin(
        load_config(),
        TwinOptions(firmware="avr", world="empty", firmware_params=AvrParams(serial_pty=str(path))),
    )
    attach_recorder(twin)
    twin.firmware.pacer.rate = 50.0  # the pacing's rate: 50x real time keeps the test short
    fd = os.open(path, os.O_RDWR | os.O_NOCTTY | os.O_NONBLOCK)
    parser = FrameParser()
    port = twin.firmware.serial
    received = [0]

    def until(
        condition, what: str
    ) -> None:  # the kernel hands pseudo-terminal bytes over in its own time
        deadline = time.monotonic() + 30.0
        while not condition():
            assert time.monotonic() < deadline, f"not within 30 s: {what}"
            select.select([fd], [], [], 0.01)

    def exchange(seconds: float, send: bytes = b"") -> list:
        """Write ``send``, let the board see it, run ``seconds``, and read every byte the board
        wrote."""
        if send:
            os.write(fd, send)
            until(lambda: port.in_waiting >= len(send), "the host's bytes on the board's side")
        twin.advance(seconds)
        chunks = []

        def read_all() -> bool:
            try:
                chunks.append(os.read(fd, 1 << 16))
                received[0] += len(chunks[-1])
            except BlockingIOError:
                pass
            return received[0] >= port.bytes_out

        until(read_all, "the board's bytes on the host's side")
        return parser.feed(b"".join(chunks))

    yield twin, exchange, parser
    os.close(fd)
    twin.firmware.close()
    assert not path.is_symlink()


def test_the_board_takes_commands_but_publishes_nothing_before_a_host_negotiates(link):
    twin, exchange, _parser = link
    frames = exchange(4.0, frame(100, serialize_float64_multiarray([1.0, 40.0, 1.0, 40.0])))
    assert frames == []  # no wheel speed, no time request: the host has not configured the board
    assert recorder_of(twin).series().true_rpm[-1] == pytest.approx(
        [40.0, 40.0], abs=6.0
    )  # yet the command ran


def test_a_topic_request_is_answered_with_the_topics_and_a_time_request_then_speeds_flow(link):
    twin, exchange, parser = link
    frames = exchange(0.2, topic_request())
    infos = [
        (f.topic_id, TopicInfo.deserialize(f.message).topic_name)
        for f in frames
        if f.topic_id in (0, 1)
    ]
    assert infos == [
        (ID_PUBLISHER, "wheel0_Vel"),
        (ID_PUBLISHER, "wheel1_Vel"),
        (ID_SUBSCRIBER, "wheel_Command"),
    ]
    assert [f.topic_id for f in frames if f.topic_id not in (0, 1)][:1] == [ID_TIME]
    speeds = [
        f
        for f in exchange(3.0, frame(ID_TIME, struct.pack("<II", 1000, 0)))
        if f.topic_id in (125, 126)
    ]
    assert len(speeds) >= 2 and all(30.0 < struct.unpack("<d", f.message)[0] < 50.0 for f in speeds)
    assert twin.firmware.negotiations == 1


def test_renegotiating_while_both_wheels_publish_corrupts_no_frame(link):
    # a speed sample is published from the SC interrupt: ros_lib writes it from main context, so it
    # never lands inside a negotiation's TopicInfo frames (which the same buffer once carried)
    twin, exchange, parser = link
    frames = []
    for _ in range(40):
        frames += exchange(0.05, topic_request() + frame(ID_TIME, struct.pack("<II", 1000, 0)))
    assert parser.dropped == 0
    answers = [f for f in frames if f.topic_id == ID_PUBLISHER]
    assert len(answers) == 2 * 40 and sum(f.topic_id in (125, 126) for f in frames) >= 2


def test_tx_stop_and_silence_stop_the_board_publishing(link):
    twin, exchange, _parser = link
    frames = exchange(3.0, frame(ID_TX_STOP, b""))
    assert not [
        f for f in frames if f.topic_id in (125, 126)
    ]  # the host shut down: nothing published
    exchange(0.1, topic_request())
    frames = exchange(16.0)  # configured again, but no answer to its time requests for 15 s
    late = [f for f in frames if f.topic_id in (125, 126)]
    assert late and sum(f.topic_id == ID_TIME for f in frames) >= 2
    assert not exchange(3.0)  # it took the host for gone: silent
