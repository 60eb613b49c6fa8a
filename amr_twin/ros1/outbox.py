"""The bridge's messages written to their subscribers at their simulated instants: :class:`Outbox`.

rospy's ``Publisher.publish`` costs about 6 us of Python a message (its lock, genpy's buffer
round trip, the statistics) on top of one ``sendall`` a message and subscriber. The bridge writes
its messages itself (:mod:`amr_twin.ros1.serialization`); the outbox keeps their TCPROS frames (a
uint32 length, then the message's bytes: what rospy's publish writes) by simulated instant and
publisher, and writes them through rospy's own transports (``write_data``): the bytes on the wire
are rospy's, only the writes are fewer.

:meth:`Outbox.release` writes them as a ROS node would, each when it is stamped: at each multiple of
``period_us`` (the ``/clock`` period), once ``wait`` has brought the wall clock to it, the ``lead``
publisher's frames (``/clock``) first, then every other message of an instant up to it, one write a
publisher and connection. No message is written before a ``/clock`` at or after its instant. Without
``wait`` (a twin running as fast as it can) everything due goes at once, ``/clock`` first: one write
a publisher and connection, however many instants. Within a publisher the instants' order is kept. A
connection whose write fails is closed, as rospy's publish closes it (rospy then drops it).
"""

from __future__ import annotations

import bisect
import struct

_LEN = struct.Struct("<I")
NEVER_US = 1 << 62
GAP_US = 1_000
"""Simulated us between a ``/clock`` and the other messages of its instant, paced. A subscriber
reads each topic in a thread of its own: an IMU message written right after its clock was handled
before it ~11 % of the time here (queue_size=1, rospy), 1 ms later ~1.5 % (its clock thread woken
late on a busy machine)."""


class _Queue:
    """One publisher's frames waiting, with their instants (in put order; ``ordered`` while never
    decreasing)."""

    __slots__ = ("times", "frames", "ordered")

    def __init__(self):
        self.times: list[int] = []
        self.frames: list = []
        self.ordered = True

    def take(self, until_us: int) -> tuple[int, list]:
        """The first instant and the frames of the instants up to ``until_us`` (instant order, then
        put order), removed."""
        times, frames = self.times, self.frames
        if not self.ordered:
            order = sorted(
                range(len(times)), key=times.__getitem__
            )  # stable: put order within an instant
            times[:] = [times[i] for i in order]
            frames[:] = [frames[i] for i in order]
            self.ordered = True
        k = bisect.bisect_right(times, until_us)
        first = times[0] if k else NEVER_US
        due = frames[:k]
        del times[:k], frames[:k]
        return first, due


class Outbox:
    """Frames waiting to be written, by rospy publisher, with their instants (see the module
    notes)."""

    def __init__(self, period_us: int = 10_000, lead=None, gap_us: int = GAP_US):
        self.period_us, self.gap_us = int(period_us), int(gap_us)
        self.lead = lead
        """The publisher written first at each release (``/clock``), or None."""
        self._queues: dict = {}  # publisher impl -> _Queue
        self.released_us = -1
        """The last instant :meth:`release` brought the wall clock to."""
        self.messages = 0
        """Messages written so far (each counted once, whatever its subscribers)."""
        self.writes = 0
        """Socket writes so far."""

    @staticmethod
    def wanted(pub) -> bool:
        """Whether ``pub`` (a rospy Publisher) has a subscriber now (no lock: rospy replaces the
        list)."""
        impl = pub.impl
        return impl is not None and bool(impl.connections)

    def _queue(self, impl, t_us: int) -> _Queue:
        """``impl``'s queue, about to take frames from instant ``t_us`` on."""
        q = self._queues.get(impl)
        if q is None:
            q = self._queues[impl] = _Queue()
        elif q.times and t_us < q.times[-1]:
            q.ordered = False
        return q

    def put(self, pub, payload: bytes, t_us: int = 0) -> None:
        """Queue ``payload`` (a message serialised in the ROS 1 format, of simulated instant
        ``t_us``)."""
        q = self._queues.get(
            pub.impl
        )  # _queue's work, inlined: the tap's path, a few thousand a second
        if q is None:
            q = self._queues[pub.impl] = _Queue()
        times = q.times
        if times and t_us < times[-1]:
            q.ordered = False
        times.append(t_us)
        q.frames.append(_LEN.pack(len(payload)) + payload)

    def feeder(self, pub, writer):
        """A bus tap ``feed(topic, msg, t_us)``: while ``pub`` has a subscriber, queue
        ``writer(msg)`` (a message's ROS 1 bytes) of simulated instant ``t_us``, as :meth:`put`
        would (a high-rate topic's path: its queue looked up once, not at every message; made at
        the first, so that the publishers' order in a write is put's)."""
        impl = pub.impl
        q = times = frames = None  # the queue, made at the first message as put makes it
        pack = _LEN.pack

        def feed(_topic: str, msg, t_us: int) -> None:
            nonlocal q, times, frames
            if impl.connections:
                if q is None:
                    q = self._queue(impl, t_us)
                    times, frames = q.times, q.frames
                if times and t_us < times[-1]:
                    q.ordered = False
                payload = writer(msg)
                times.append(t_us)
                frames.append(pack(len(payload)) + payload)

        return feed

    def put_block(self, pub, t_us: list, block: bytes) -> None:
        """Queue the frames of ``block`` (TCPROS frames of equal lengths, one after the other: a
        length, then a message), the i-th of simulated instant ``t_us[i]`` (never decreasing), as
        that many :meth:`put` would."""
        n = len(t_us)
        if not n:
            return
        q = self._queue(pub.impl, t_us[0])
        size, view = len(block) // n, memoryview(block)
        q.times += t_us
        q.frames += [view[i : i + size] for i in range(0, n * size, size)]

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
        """The frames of the instants up to ``until_us``, by publisher impl: the lead's first, then
        the others in the order of their earliest instant."""
        lead = getattr(self.lead, "impl", None)
        due = []
        for impl, q in self._queues.items():
            if q.times and (q.times[0] <= until_us or not q.ordered):
                first, frames = q.take(until_us)
                if frames:
                    due.append((-1 if impl is lead else first, len(due), impl, frames))
        due.sort(key=lambda d: d[:2])
        return {impl: frames for _first, _i, impl, frames in due}

    def _send(self, frames, impl) -> None:
        if not frames:
            return
        self.messages += len(frames)
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
