"""The rosserial serial protocol as bytes: frames, their checksums, and the messages they carry.

A frame (rosserial protocol version 2, ``rosserial_python``'s ``serial_node.py``)::

    0xff | 0xfe | len lo | len hi | 255 - (len lo + len hi) % 256
    | topic id lo | topic id hi | message (len bytes) | 255 - (topic id bytes + message) % 256

Topic id 0 carries the topic negotiation (``rosserial_msgs/TopicInfo``: the PC sends an empty
frame on id 0 and the client answers one TopicInfo per publisher on id 0 and per subscriber on
id 1); application topics use ids from 100. Messages are ROS 1 serialised (little-endian,
strings and arrays prefixed by a uint32 length).

:class:`FrameParser` is the receiving side, fed byte by byte as the UART delivers them; it
resynchronises on the next 0xff after a bad length checksum or message checksum and counts
the frames it dropped.
"""

from __future__ import annotations

import struct
from dataclasses import dataclass
from typing import Sequence

PROTOCOL_VERSION = 0xFE
"""Second byte of every frame (rosserial since ROS Groovy)."""

ID_PUBLISHER, ID_SUBSCRIBER, ID_TIME, ID_TX_STOP = 0, 1, 10, 11
"""Topic ids of rosserial's own messages (rosserial_msgs/TopicInfo constants)."""

MD5SUM = {
    "std_msgs/Float64": "fdb28210bfa9d7c91146260178d9a584",
    "std_msgs/Float64MultiArray": "4b7d974086d4060e7db4613a7e6c3ba4",
}
"""ROS 1 md5sums of the message types the twin's rosserial bridge carries."""


def frame(topic_id: int, message: bytes) -> bytes:
    """The frame that carries ``message`` (serialised) on ``topic_id``."""
    n = len(message)
    if n > 0xFFFF:
        raise ValueError(f"a rosserial message holds at most 65535 bytes, got {n}")
    lo, hi = n & 0xFF, n >> 8
    tid = struct.pack("<H", topic_id)
    return (
        bytes((0xFF, PROTOCOL_VERSION, lo, hi, 255 - (lo + hi) % 256))
        + tid
        + message
        + bytes((255 - (sum(tid) + sum(message)) % 256,))
    )


def topic_request() -> bytes:
    """What serial_node sends to ask the client for its topics."""
    return frame(ID_PUBLISHER, b"")


def serialize_float64(value: float) -> bytes:
    """std_msgs/Float64."""
    return struct.pack("<d", value)


def deserialize_float64(message: bytes) -> float:
    """std_msgs/Float64 -> its ``data``."""
    return struct.unpack_from("<d", message)[0]


def serialize_float64_multiarray(data: Sequence[float], data_offset: int = 0) -> bytes:
    """std_msgs/Float64MultiArray with an empty ``layout.dim`` (as the thesis sends it, fig.
    3.3)."""
    return struct.pack(f"<III{len(data)}d", 0, data_offset, len(data), *data)


def deserialize_float64_multiarray(message: bytes) -> list[float]:
    """std_msgs/Float64MultiArray -> its ``data`` (dimensions skipped)."""
    (n_dim,), o = struct.unpack_from("<I", message), 4
    for _ in range(n_dim):
        (label,) = struct.unpack_from("<I", message, o)
        o += 4 + label + 8
    _offset, n = struct.unpack_from("<II", message, o)
    return list(struct.unpack_from(f"<{n}d", message, o + 8))


@dataclass(frozen=True)
class TopicInfo:
    """rosserial_msgs/TopicInfo: one topic a client publishes or subscribes."""

    topic_id: int
    topic_name: str
    message_type: str
    md5sum: str
    buffer_size: int

    @classmethod
    def deserialize(cls, message: bytes) -> "TopicInfo":
        (topic_id,), o = struct.unpack_from("<H", message), 2
        strings = []
        for _ in range(3):
            (n,) = struct.unpack_from("<I", message, o)
            strings.append(message[o + 4 : o + 4 + n].decode())
            o += 4 + n
        (buffer_size,) = struct.unpack_from("<i", message, o)
        return cls(topic_id, *strings, buffer_size)


@dataclass(frozen=True)
class Frame:
    """A received frame: topic id, message bytes, and the stream index of its first and last
    byte."""

    topic_id: int
    message: bytes
    first: int
    last: int


class FrameParser:
    """rosserial frames from a byte stream; :meth:`feed` returns the frames completed."""

    def __init__(self):
        self._buf = bytearray()
        self._start = 0  # stream index of _buf[0]
        self.dropped = 0
        """Frames dropped for a bad length or message checksum."""

    @property
    def pending(self) -> tuple[int, int | None]:
        """Bytes of an unfinished frame received so far, and its total length once known (or
        None)."""
        if len(self._buf) >= 5:
            return len(self._buf), 8 + (self._buf[2] | self._buf[3] << 8)
        return len(self._buf), None

    def feed(self, data: bytes) -> list[Frame]:
        out = []
        for byte in data:
            if not self._buf:
                if byte == 0xFF:
                    self._buf.append(byte)
                self._start += 1
                continue
            self._buf.append(byte)
            self._start += 1
            out.extend(self._check())
        return out

    def _restart(self, drop: bool) -> list[Frame]:
        """Drop the frame in progress and look for the next 0xff inside what it held."""
        self.dropped += drop
        rest = bytes(self._buf[1:])
        self._buf.clear()
        self._start -= len(rest)
        return self.feed(rest)

    def _check(self) -> list[Frame]:
        b = self._buf
        n = len(b)
        if n == 2 and b[1] != PROTOCOL_VERSION:
            return self._restart(False)
        if n == 5 and (b[2] + b[3] + b[4]) % 256 != 255:
            return self._restart(True)
        if n >= 5:
            length = b[2] | b[3] << 8
            if n == 8 + length:
                if (sum(b[5:]) % 256) != 255:
                    return self._restart(True)
                first = self._start - n
                done = Frame(b[5] | b[6] << 8, bytes(b[7 : 7 + length]), first, self._start - 1)
                b.clear()
                return [done]
        return []
