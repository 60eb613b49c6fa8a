"""Virtual microsecond clock and event queue shared by firmware, bus and sensors.

Every component that acts at its own instants (the Arduino's timer interrupt, the
end of a ``delay()``, a rosserial frame arriving, a LiDAR beam) schedules a
callback on one :class:`VirtualClock`. The simulation loop asks for
:meth:`VirtualClock.next_event_us`, advances the physics in C up to that instant,
then calls :meth:`VirtualClock.run_until` which fires the callbacks in time order
with :attr:`VirtualClock.now_us` set to each callback's own time.

Time is an integer number of microseconds (``t_us``), like the Arduino's
``micros()``, so that event times are exact and ordering is deterministic.
"""

from __future__ import annotations

import heapq
import itertools
from dataclasses import dataclass, field
from typing import Callable

NEVER_US = 2**62
"""Sentinel time of an empty queue (about 146 000 years)."""


@dataclass(order=True)
class _Event:
    t_us: int
    seq: int
    callback: Callable[[], None] = field(compare=False)
    cancelled: bool = field(default=False, compare=False)


class EventHandle:
    """Returned by :meth:`VirtualClock.schedule`; lets the owner cancel the event."""

    __slots__ = ("_event",)

    def __init__(self, event: _Event):
        self._event = event

    @property
    def t_us(self) -> int:
        """Time at which the event fires, microseconds."""
        return self._event.t_us

    def cancel(self) -> None:
        """Prevent the callback from running (no effect if it already ran)."""
        self._event.cancelled = True


class VirtualClock:
    """A simulated microsecond clock with a time-ordered queue of callbacks.

    Events scheduled for the same instant run in the order they were scheduled.
    """

    def __init__(self, start_us: int = 0):
        self.now_us: int = int(start_us)
        self._queue: list[_Event] = []
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
    def schedule(self, t_us: int, callback: Callable[[], None]) -> EventHandle:
        """Run ``callback`` at absolute time ``t_us`` (not before ``now_us``)."""
        t_us = int(t_us)
        if t_us < self.now_us:
            raise ValueError(f"t_us={t_us} is in the past (now_us={self.now_us})")
        event = _Event(t_us, next(self._seq), callback)
        heapq.heappush(self._queue, event)
        return EventHandle(event)

    def schedule_in(self, delay_us: int, callback: Callable[[], None]) -> EventHandle:
        """Run ``callback`` ``delay_us`` microseconds from now."""
        return self.schedule(self.now_us + int(delay_us), callback)

    def next_event_us(self) -> int:
        """Time of the earliest pending event, or :data:`NEVER_US` if none."""
        queue = self._queue
        while queue and queue[0].cancelled:
            heapq.heappop(queue)
        return queue[0].t_us if queue else NEVER_US

    def run_until(self, t_us: int) -> int:
        """Fire every event with time <= ``t_us`` in order; leave ``now_us = t_us``.

        Returns the number of callbacks run. Callbacks may schedule new events;
        those due at or before ``t_us`` run in the same call.
        """
        t_us = int(t_us)
        if t_us < self.now_us:
            raise ValueError(f"cannot run backwards to {t_us} (now_us={self.now_us})")
        queue = self._queue
        fired = 0
        while queue and queue[0].t_us <= t_us:
            event = heapq.heappop(queue)
            if event.cancelled:
                continue
            self.now_us = event.t_us
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
