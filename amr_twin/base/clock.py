"""Virtual microsecond clock and event queue shared by firmware, bus and sensors.

Every component that acts at its own instants (the Arduino's timer interrupt, the
end of a ``delay()``, a rosserial frame arriving, a LiDAR beam) schedules a
callback on one :class:`VirtualClock`. The simulation loop asks for the next
event, advances the physics in C up to that instant, then calls
:meth:`VirtualClock.run_until` which fires the callbacks in time order with
:attr:`VirtualClock.now_us` set to each callback's own time.

Two kinds of event share one time order (ties: the order of scheduling):

- a *synced* event (the default) may read or write the physics, so the loop
  brings the physics up to its instant before it runs;
- a *publishing* event (``schedule(..., publishes=topics)``) reads no physics
  state and acts on the rest of the twin only by publishing on ``topics``
  (odometry, a sensor message sampled earlier). The loop may run it while the
  physics is ahead of it, as far as the bus' lookahead for those topics allows
  (:meth:`amr_twin.ros.bus.Bus.lookahead_us`): no subscriber, no limit.

A periodic event (:meth:`VirtualClock.schedule_every`, a ROS timer) is queued again one
period later as it fires, before its callback runs: the same order as a callback that
schedules its next occurrence first, without a new event each time.

Time is an integer number of microseconds (``t_us``), like the Arduino's
``micros()``, so that event times are exact and ordering is deterministic.
"""

from __future__ import annotations

import heapq
import itertools
from typing import Callable, Sequence

NEVER_US = 2**62
"""Sentinel time of an empty queue (about 146 000 years)."""


class _Event:
    __slots__ = ("t_us", "callback", "publishes", "cancelled", "period_us")

    def __init__(
        self,
        t_us: int,
        callback: Callable[[], None],
        publishes: tuple[str, ...] | None,
        period_us: int = 0,
    ):
        self.t_us, self.callback, self.publishes, self.cancelled = t_us, callback, publishes, False
        self.period_us = period_us


class EventHandle:
    """Returned by :meth:`VirtualClock.schedule`; lets the owner cancel the event."""

    __slots__ = ("_event",)

    def __init__(self, event: _Event):
        self._event = event

    @property
    def t_us(self) -> int:
        """Time at which the event fires (next), microseconds."""
        return self._event.t_us

    @property
    def publishes(self) -> tuple[str, ...] | None:
        """Topics of a publishing event, ``None`` for a synced one."""
        return self._event.publishes

    def cancel(self) -> None:
        """Prevent the callback from running (no effect if it already ran)."""
        self._event.cancelled = True


class VirtualClock:
    """A simulated microsecond clock with a time-ordered queue of callbacks.

    Events scheduled for the same instant run in the order they were scheduled,
    whatever their kind. The queues hold ``(t_us, seq, event)`` tuples (compared
    in C); synced and publishing events are kept in two heaps.
    """

    def __init__(self, start_us: int = 0):
        self.now_us: int = int(start_us)
        self._queue: list[tuple[int, int, _Event]] = []  # synced events
        self._free: list[tuple[int, int, _Event]] = []  # publishing events
        self._seq = itertools.count()

    # -- Arduino-style readings -------------------------------------------------
    def micros(self) -> int:
        """Current time in microseconds (wraps like the Arduino's after 2**32)."""
        return self.now_us & 0xFFFFFFFF

    def millis(self) -> int:
        """Current time in milliseconds (wraps like the Arduino's after 2**32)."""
        return (self.now_us // 1000) & 0xFFFFFFFF

    @property
    def now_s(self) -> float:
        """Current time in seconds."""
        return self.now_us * 1e-6

    # -- scheduling ---------------------------------------------------------------
    def schedule(
        self, t_us: int, callback: Callable[[], None], publishes: Sequence[str] | None = None
    ) -> EventHandle:
        """Run ``callback`` at absolute time ``t_us`` (not before ``now_us``).

        Parameters
        ----------
        t_us : int
            Absolute time, microseconds.
        callback : callable
            Called with no argument, with ``now_us == t_us``.
        publishes : sequence of str, optional
            Declares a publishing event: the callback reads no physics state and
            only publishes on these topics (a tuple of names without a leading
            ``/``, other sequences are normalised; ``()``: nothing that any other
            node sees). ``None``: a synced event.
        """
        t_us = int(t_us)
        if t_us < self.now_us:
            raise ValueError(f"t_us={t_us} is in the past (now_us={self.now_us})")
        topics = publishes
        if topics is not None and type(topics) is not tuple:
            topics = tuple(p.lstrip("/") for p in topics)
        event = _Event(t_us, callback, topics)
        heapq.heappush(
            self._queue if topics is None else self._free, (t_us, next(self._seq), event)
        )
        return EventHandle(event)

    def schedule_every(
        self,
        first_us: int,
        period_us: int,
        callback: Callable[[], None],
        publishes: Sequence[str] | None = None,
    ) -> EventHandle:
        """Run ``callback`` at ``first_us`` and then every ``period_us`` until the handle is
        cancelled.

        Each occurrence is queued as the previous one fires, before its callback runs (see
        :meth:`schedule` for ``publishes``).
        """
        period_us = int(period_us)
        if period_us <= 0:
            raise ValueError(f"period_us={period_us} must be > 0")
        handle = self.schedule(first_us, callback, publishes)
        handle._event.period_us = period_us
        return handle

    def schedule_in(
        self, delay_us: int, callback: Callable[[], None], publishes: Sequence[str] | None = None
    ) -> EventHandle:
        """Run ``callback`` ``delay_us`` microseconds from now (see :meth:`schedule`)."""
        return self.schedule(self.now_us + int(delay_us), callback, publishes)

    @staticmethod
    def _top(queue: list) -> int:
        while queue and queue[0][2].cancelled:
            heapq.heappop(queue)
        return queue[0][0] if queue else NEVER_US

    def next_event_us(self) -> int:
        """Time of the earliest pending event of either kind, or :data:`NEVER_US` if none."""
        return min(self._top(self._queue), self._top(self._free))

    def next_synced_event_us(self) -> int:
        """Time of the earliest pending synced event, or :data:`NEVER_US` if none."""
        return self._top(self._queue)

    def physics_horizon_us(self, t_us: int, lookahead_us: Callable[[tuple[str, ...]], int]) -> int:
        """How far the physics may run ahead of the pending publishing events.

        Parameters
        ----------
        t_us : int
            The loop's target (the next synced event, the end of the run), us.
        lookahead_us : callable
            ``lookahead_us(topics)``: the earliest delay after which a message on
            ``topics`` can act on anything that reads the physics, us
            (:meth:`amr_twin.ros.bus.Bus.lookahead_us`).

        Returns
        -------
        int
            ``min(t_us, t_e + lookahead_us(topics_e))`` over the publishing events
            ``e`` due at or before the result, us.
        """
        for t_e, _seq, event in self._free:  # a handful: one per periodic publisher
            if t_e <= t_us and not event.cancelled:
                t_us = min(t_us, t_e + lookahead_us(event.publishes))
        return t_us

    def run_until(self, t_us: int) -> int:
        """Fire every event with time <= ``t_us`` in order; leave ``now_us = t_us``.

        Returns the number of callbacks run. Callbacks may schedule new events;
        those due at or before ``t_us`` run in the same call.
        """
        t_us = int(t_us)
        if t_us < self.now_us:
            raise ValueError(f"cannot run backwards to {t_us} (now_us={self.now_us})")
        synced, free, pop = self._queue, self._free, heapq.heappop
        fired = 0
        while True:
            if synced and synced[0][0] <= t_us:
                queue = free if free and free[0] < synced[0] else synced
            elif free and free[0][0] <= t_us:
                queue = free
            else:
                break
            t_e, _seq, event = pop(queue)
            if event.cancelled:
                continue
            self.now_us = t_e
            if event.period_us:  # periodic: the next occurrence is queued first
                event.t_us = t_next = t_e + event.period_us
                heapq.heappush(queue, (t_next, next(self._seq), event))
            event.callback()
            fired += 1
        self.now_us = t_us
        return fired

    def set_time(self, t_us: int) -> None:
        """Move ``now_us`` forward to ``t_us`` without running events.

        Used by the loop to stamp an interrupt (a hall edge) that falls between
        queued events; it refuses to skip over a pending event.
        """
        t_us = int(t_us)
        if t_us < self.now_us:
            raise ValueError(f"cannot move backwards to {t_us} (now_us={self.now_us})")
        if t_us > self.next_event_us():
            raise ValueError(f"t_us={t_us} would skip an event due at {self.next_event_us()}")
        self.now_us = t_us
