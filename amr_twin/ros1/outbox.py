"""The bridge's messages written to their subscribers at their simulated instants: :class:`Outbox`.

rospy's ``Publisher.publish`` costs about 6 us of Python a message (its lock, genpy's buffer
round trip, the statistics) on top of one ``sendall`` a message and subscriber. The bridge writes
its messages itself (:mod:`amr_twin.ros1.serialization`); the outbox keeps their TCPROS frames (a
uint32 length, then the message's bytes: what rospy's publish writes) by simulated instant and
publisher, and writes them through rospy's own transports (``write_data``): the bytes on the wire are
rospy's, only the writes are fewer.

:meth:`Outbox.release` writes them as a ROS node would, each when it is stamped: at each multiple of
``period_us`` (the ``/clock`` period), once ``wait`` has brought the wall clock to it, the ``lead``
publisher's frames (``/clock``) first, then every other message of an instant up to it, one write a
publisher and connection. No message is written before a ``/clock`` at or after its instant. Without
``wait`` (a twin running as fast as it can) everything due goes at once, ``/clock`` first: one write a
publisher and connection, however many instants. Within a publisher the instants' order is kept. A
connection whose write fails is closed, as rospy's publish closes it (rospy then drops it).
"""

from __future__ import annotations

import struct

_LEN = struct.Struct("<I")
NEVER_US = 1 << 62
GAP_US = 1_000
"""Simulated us between a ``/clock`` and the other messages of its instant, paced. A subscriber reads each
topic in a thread of its own: an IMU message written right after its clock was handled before it ~11 % of
the time here (queue_size=1, rospy), 1 ms later ~1.5 % (its clock thread woken late on a busy machine)."""


class Outbox:
    """Frames waiting to be written, by instant and rospy publisher (see the module notes)."""

    def __init__(self, period_us: int = 10_000, lead=None, gap_us: int = GAP_US):
        self.period_us, self.gap_us = int(period_us), int(gap_us)
        self.lead = lead
        """The publisher written first at each release (``/clock``), or None."""
        self._groups: dict = {}  # instant us -> {publisher impl: [length, bytes, ...]}
        self._last: tuple = (None, None)  # the instant put last and its group (most puts share it)
        self.released_us = -1
        """The last instant :meth:`release` brought the wall clock to."""
        self.messages = 0
        """Messages written so far (each counted once, whatever its subscribers)."""
        self.writes = 0
        """Socket writes so far."""

    @staticmethod
    def wanted(pub) -> bool:
        """Whether ``pub`` (a rospy Publisher) has a subscriber now (no lock: rospy replaces the list)."""
        impl = pub.impl
        return impl is not None and bool(impl.connections)

    def put(self, pub, payload: bytes, t_us: int = 0) -> None:
        """Queue ``payload`` (a message serialised in the ROS 1 format, of simulated instant ``t_us``)."""
        last_t, group = self._last
        if last_t != t_us:
            group = self._groups.get(t_us)
            if group is None:
                group = self._groups[t_us] = {}
            self._last = (t_us, group)
        frames = group.get(pub.impl)
        if frames is None:
            frames = group[pub.impl] = []
        frames += (_LEN.pack(len(payload)), payload)

    def release(self, until_us: int, wait=None) -> None:
        """Write every message of an instant up to ``until_us``: at each ``period_us`` point after
        ``wait(point)`` returns (the pacer's sleep), or all at once without ``wait``."""
        if wait is None:
            self._write(until_us)
            self.released_us = max(self.released_us, until_us)
            return
        self._write(self.released_us)  # instants already passed (published after their point): now
        point = (self.released_us // self.period_us + 1) * self.period_us
        while point <= until_us:
            wait(point)
            self.released_us = point
            merged = self._take(point)
            lead = getattr(self.lead, "impl", None)
            self._send(merged.pop(lead, None), lead)
            if merged:
                wait(point + self.gap_us)
                for impl, frames in merged.items():
                    self._send(frames, impl)
            point += self.period_us

    def flush(self) -> None:
        """Write everything queued, whatever its instant (the end of a run)."""
        self._write(NEVER_US)

    def _write(self, until_us: int) -> None:
        for impl, frames in self._take(until_us).items():
            self._send(frames, impl)

    def _take(self, until_us: int) -> dict:
        """The frames of the instants up to ``until_us``, by publisher impl, the lead's first."""
        due = sorted(t for t in self._groups if t <= until_us)
        if not due:
            return {}
        self._last = (None, None)
        merged: dict = {}
        lead = getattr(self.lead, "impl", None)
        if lead is not None:
            merged[lead] = []
        for t in due:
            for impl, frames in self._groups.pop(t).items():
                have = merged.get(impl)
                if have is None:
                    merged[impl] = frames
                else:
                    have += frames
        return merged

    def _send(self, frames, impl) -> None:
        if not frames:
            return
        self.messages += len(frames) // 2
        if not impl.closed:
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
