"""The bridge's messages written to their subscribers a batch at a time: :class:`Outbox`.

rospy's ``Publisher.publish`` costs about 6 us of Python a message (its lock, genpy's buffer
round trip, the statistics) on top of one ``sendall`` a message and subscriber, and each such
write wakes the subscriber up. The bridge writes its high-rate messages itself
(:mod:`amr_twin.ros1.serialization`); the outbox keeps their TCPROS frames (a uint32 length,
then the message's bytes: what rospy's publish writes) per publisher, and :meth:`Outbox.flush`
writes each publisher's frames to each of its connections in one write, through rospy's own
transports (``write_data``). The bytes on the wire are rospy's: only the writes are fewer.

Within a topic the order is kept; a subscriber receives a flush's messages together (the
bridge flushes at the pacer's ticks: every 20 ms of simulated time, or every 200 ms when
unpaced). A connection whose write fails is closed, as rospy's publish closes it (rospy then
drops it from the publisher).
"""

from __future__ import annotations

import struct

_LEN = struct.Struct("<I")


class Outbox:
    """Frames waiting for :meth:`flush`, per rospy publisher (see the module notes)."""

    def __init__(self):
        self._frames: dict = {}  # publisher impl -> [length, bytes, length, bytes, ...]
        self.messages = 0
        """Messages written so far (each counted once, whatever its subscribers)."""
        self.writes = 0
        """Socket writes so far."""

    @staticmethod
    def wanted(pub) -> bool:
        """Whether ``pub`` (a rospy Publisher) has a subscriber now (no lock: rospy replaces the list)."""
        impl = pub.impl
        return impl is not None and bool(impl.connections)

    def put(self, pub, payload: bytes) -> None:
        """Queue ``payload`` (a message serialised in the ROS 1 format) for ``pub``'s subscribers."""
        frames = self._frames.get(pub.impl)
        if frames is None:
            frames = self._frames[pub.impl] = []
        frames += (_LEN.pack(len(payload)), payload)

    def flush(self) -> None:
        """Write every publisher's frames to each of its connections, one write each."""
        if not self._frames:
            return
        pending, self._frames = self._frames, {}
        for impl, frames in pending.items():
            self.messages += len(frames) // 2
            if impl.closed:
                continue
            data = b"".join(frames)
            for conn in impl.connections:
                try:
                    conn.write_data(data)
                    self.writes += 1
                except Exception:  # noqa: BLE001 - as rospy's publish: a broken subscriber is closed, not fatal
                    try:
                        conn.close()
                    except Exception:  # noqa: BLE001
                        pass
