"""In-process ROS-like bus on simulation time: topics, services, taps and a tf buffer.

Reasons and measurements: docs/how-to/ros1.md#amr_twinrosbus."""

from __future__ import annotations

from collections import deque
from typing import Any, Callable

from amr_twin.base.clock import NEVER_US, EventHandle, VirtualClock
from amr_twin.ros.geometry_messages import TFMessage, TransformStamped
from amr_twin.ros.tf_buffer import TfBuffer

Tap = Callable[[str, Any, int], None]


class ServiceCallError(RuntimeError):
    """A service call failed: no server advertised, or the server raised."""


def _name(name: str) -> str:
    return name.lstrip("/")


class Subscription:
    """One subscriber of a topic; created by :meth:`Bus.subscribe`."""

    def __init__(
        self,
        bus: Bus,
        topic: str,
        callback: Callable[[Any], None],
        queue_size: int,
        latency_us: int,
    ):
        self.bus, self.topic, self.callback = bus, topic, callback
        self.queue_size, self.latency_us = int(queue_size), int(latency_us)
        self.dropped = 0
        """Messages dropped because ``queue_size`` were already in flight."""
        self._pending: deque[tuple[Any, EventHandle]] = deque()
        self.active = True

    def _enqueue(self, msg: Any) -> None:
        if self.latency_us <= 0:
            self.callback(msg)
            return
        if self.queue_size > 0 and len(self._pending) >= self.queue_size:
            self._pending.popleft()[1].cancel()
            self.dropped += 1
        handle = self.bus.clock.schedule_in(self.latency_us, self._deliver)
        self._pending.append((msg, handle))

    def _deliver(self) -> None:
        msg, _ = self._pending.popleft()
        if self.active:
            self.callback(msg)

    def unregister(self) -> None:
        """Stop receiving; messages in flight are discarded."""
        self.active = False
        for _, handle in self._pending:
            handle.cancel()
        self._pending.clear()
        subs = self.bus._subs.get(self.topic, [])
        if self in subs:
            subs.remove(self)
            self.bus.version += 1


class Publisher:
    """Handle returned by :meth:`Bus.advertise`."""

    def __init__(self, bus: Bus, topic: str, msg_type: type | None, queue_size: int):
        self.bus, self.topic, self.msg_type, self.queue_size = bus, topic, msg_type, queue_size

    def publish(self, msg: Any) -> None:
        """Publish ``msg`` on this publisher's topic."""
        self.bus.publish(self.topic, msg)


class Bus:
    """Topics, services, taps and tf for all the twin's nodes, on one clock.

    Parameters
    ----------
    clock : VirtualClock
        The shared simulation clock; delayed deliveries are events on it.
    """

    def __init__(self, clock: VirtualClock):
        self.clock = clock
        self._subs: dict[str, list[Subscription]] = {}
        self.version = 0
        """Counts the changes of the subscriptions (what :meth:`lookahead_us` reads)."""
        self._types: dict[str, type] = {}
        self._latched: dict[str, Any] = {}
        self._services: dict[str, Callable[[Any], Any]] = {}
        self._taps: list[tuple[Tap, frozenset[str] | None]] = []  # (tap, its topics or None: all)
        self._taps_by_topic: dict[
            str, tuple[Tap, ...]
        ] = {}  # each topic's taps, in the order added
        self._static: dict[str, TransformStamped] = {}
        self._intercepts: dict[str, Callable[[Any], Any]] = {}
        self.tf = TfBuffer()

    # -- topics -----------------------------------------------------------------
    def advertise(
        self, topic: str, msg_type: type | None = None, queue_size: int = 10, latch: bool = False
    ) -> Publisher:
        """Declare a topic; with ``msg_type`` set, later publishes are type-checked."""
        topic = _name(topic)
        if msg_type is not None:
            known = self._types.setdefault(topic, msg_type)
            if known is not msg_type:
                raise TypeError(
                    f"topic {topic!r} carries {known.__name__}, not {msg_type.__name__}"
                )
        if latch:
            self._latched.setdefault(topic, None)
        return Publisher(self, topic, msg_type, queue_size)

    def subscribe(
        self, topic: str, callback: Callable[[Any], None], queue_size: int = 10, latency_us: int = 0
    ) -> Subscription:
        """Call ``callback(msg)`` for each message on ``topic``, ``latency_us`` after
        publication."""
        topic = _name(topic)
        sub = Subscription(self, topic, callback, queue_size, latency_us)
        self._subs.setdefault(topic, []).append(sub)
        self.version += 1
        latched = self._latched.get(topic)
        if latched is not None:

            def deliver_latched() -> None:
                if sub.active:
                    sub.callback(latched)

            self.clock.schedule_in(max(sub.latency_us, 0), deliver_latched)
        return sub

    def publish(self, topic: str, msg: Any) -> None:
        """Hand ``msg`` to the taps, then to the subscribers of ``topic``."""
        if topic[:1] == "/":
            topic = topic.lstrip("/")
        known = self._types.get(topic)
        if known is not None and type(msg) is not known and not isinstance(msg, known):
            raise TypeError(f"topic {topic!r} carries {known.__name__}, got {type(msg).__name__}")
        if self._intercepts:
            intercept = self._intercepts.get(topic)
            if intercept is not None:
                msg = intercept(msg)
                if msg is None:
                    return
        if topic in self._latched:
            self._latched[topic] = msg
        taps = self._taps_by_topic.get(topic)
        if taps is None:
            taps = self._taps_of(topic)
        if taps:
            now_us = self.clock.now_us
            for tap in taps:
                tap(topic, msg, now_us)
        subs = self._subs.get(topic)
        if subs:
            for sub in tuple(subs):
                sub._enqueue(msg)

    def lookahead_us(self, topics: tuple[str, ...]) -> int:
        """Earliest delay after which a message published on ``topics`` reaches a subscriber, us.

        The smallest ``latency_us`` of the topics' subscribers,
        :data:`~amr_twin.base.clock.NEVER_US` when none subscribes: taps are observers
        and never act on the twin. The loop lets the physics run this far ahead of
        a publishing clock event (:mod:`amr_twin.base.clock`). Readers of :attr:`tf` pull
        it in their own events, which run after the publishing event in time order.
        """
        best = NEVER_US
        subs = self._subs
        for topic in topics:
            for sub in subs.get(topic, ()):
                if sub.latency_us < best:
                    best = max(sub.latency_us, 0)
        return best

    def add_tap(self, tap: Tap, topics: tuple[str, ...] | None = None) -> None:
        """Register ``tap(topic, msg, t_us)``, called for every message published on ``topics``
        (every topic when None; a service call is a message on ``<service>/request``).

        A tap observes: it must not publish, schedule or read the physics (the
        loop may run publishing events while the physics is ahead of them). Taps
        are called in the order they were added.
        """
        self._taps.append((tap, None if topics is None else frozenset(_name(t) for t in topics)))
        self._taps_by_topic.clear()

    def _taps_of(self, topic: str) -> tuple[Tap, ...]:
        taps = self._taps_by_topic[topic] = tuple(
            t for t, topics in self._taps if topics is None or topic in topics
        )
        return taps

    def intercept(self, topic: str, func: Callable[[Any], Any] | None) -> None:
        """Pass every message on ``topic`` through ``func(msg)`` before taps and subscribers.

        ``func`` returns the message to deliver (the same or another) or None to drop
        it: a node that stops publishing or publishes wrong values (fault injection,
        :mod:`amr_twin.sim.fault_injector`). ``None`` removes the interception.
        """
        if func is None:
            self._intercepts.pop(_name(topic), None)
        else:
            self._intercepts[_name(topic)] = func

    def has_tap(self, tap: Tap) -> bool:
        """Whether ``tap`` is added."""
        return any(t == tap for t, _topics in self._taps)

    def remove_tap(self, tap: Tap) -> None:
        """Unregister a tap added with :meth:`add_tap` (ValueError if it was not)."""
        for i, (t, _topics) in enumerate(self._taps):
            if t == tap:
                del self._taps[i]
                self._taps_by_topic.clear()
                return
        raise ValueError(f"{tap!r} is not a tap of this bus")

    def topics(self) -> list[str]:
        """Names of the topics advertised or subscribed so far."""
        return sorted(set(self._subs) | set(self._types) | set(self._latched))

    # -- services ---------------------------------------------------------------
    def advertise_service(self, name: str, handler: Callable[[Any], Any]) -> None:
        """Serve ``name``: ``handler(request)`` returns the response."""
        name = _name(name)
        if name in self._services:
            raise ValueError(f"service {name!r} is already advertised")
        self._services[name] = handler

    def unadvertise_service(self, name: str) -> None:
        """Withdraw a service (later calls fail with :class:`ServiceCallError`)."""
        self._services.pop(_name(name), None)

    def has_service(self, name: str) -> bool:
        """True if a server is advertised under ``name``."""
        return _name(name) in self._services

    def call_service(self, name: str, request: Any) -> Any:
        """Call a service synchronously and return its response.

        Raises
        ------
        ServiceCallError
            No server, or the server raised (the cause is chained).
        """
        topic = _name(name) + "/request"
        taps = self._taps_by_topic.get(topic)
        if taps is None:
            taps = self._taps_of(topic)
        if taps:
            now_us = self.clock.now_us
            for tap in taps:
                tap(topic, request, now_us)
        handler = self._services.get(_name(name))
        if handler is None:
            raise ServiceCallError(f"service {_name(name)!r} is not advertised")
        try:
            return handler(request)
        except Exception as exc:  # a failing server is a failed call, as in roscpp
            raise ServiceCallError(f"service {_name(name)!r} failed: {exc}") from exc

    # -- tf ---------------------------------------------------------------------
    def send_transform(
        self, transforms: TransformStamped | list[TransformStamped], static: bool = False
    ) -> None:
        """Store transforms in :attr:`tf` and publish them on ``tf`` (``tf_static`` if static).

        Static: the message carries every static transform sent so far (one per child frame).
        """
        if isinstance(transforms, TransformStamped):
            transforms = [transforms]
        for ts in transforms:
            self.tf.set_transform(ts)
        if static:
            for ts in transforms:
                self._static[ts.child_frame_id] = ts
            transforms = list(self._static.values())
        topic = "tf_static" if static else "tf"
        if static and topic not in self._latched:
            self.advertise(topic, TFMessage, latch=True)
        self.publish(topic, TFMessage(list(transforms)))

    def static_transforms(self) -> list[TransformStamped]:
        """Every static transform sent so far, one per child frame, in the order first sent."""
        return list(self._static.values())
