"""The twins and the fleet manager in lockstep through the broker, so that a run as fast as
possible is reproducible: same seed, same messages at the same simulated instants.

The manager's MQTT callback only collects the vehicles' ``state``, ``connection`` and
``factsheet`` messages. At every pacer tick (20 ms of simulated time) the twin's thread waits until
every one a vehicle published has arrived, hands them to the manager in a fixed order (by serial
number, each vehicle's in the order it sent them: the same whatever order the broker delivered
several vehicles' in), then waits until every ``order`` and ``instantActions`` the manager sent is
queued on its vehicle's pacer (they act at the next tick). The manager's events are stamped with
the simulated time of the message that caused them (its VDA 5050 ``timestamp`` on the twin's clock
from :data:`EPOCH`), or of the tick.
"""

from __future__ import annotations

import threading
import time
from datetime import datetime, timezone

from amr_twin.fleet_manager.manager import SUBSCRIBED

EPOCH = datetime(2026, 1, 1, tzinfo=timezone.utc)
"""The twins' clock at simulated time 0 (their messages' timestamps)."""
WAIT_S = 10.0
"""Wall seconds to wait for the broker at a tick before giving up."""


def sim_seconds(timestamp: str) -> float:
    """A VDA 5050 timestamp on the twins' clock as simulated seconds since :data:`EPOCH`."""
    t = datetime.strptime(timestamp, "%Y-%m-%dT%H:%M:%S.%fZ").replace(tzinfo=timezone.utc)
    return round((t - EPOCH).total_seconds(), 3)


class Lockstep:
    """Carries the messages between ``sessions`` (FleetSession-like: ``transport``, ``pacer``) and
    ``manager`` (a FleetManager) tick by tick (module docstring); ``on_tick(t_s)`` runs at every
    tick once the manager has handled all before it. Built once both sides are quiet
    (:func:`quiet`); a sink of the sessions' pacer."""

    def __init__(self, sessions: list, manager, on_tick):
        self.sessions, self.manager, self.on_tick = sessions, manager, on_tick
        self.t_s = 0.0
        self._lock = threading.Lock()
        self._published = 0
        self._arrived: list = []
        self._handled = 0
        self._queued = sum(manager.sent.values())
        for s in sessions:
            self._count_published(s.transport)
            self._count_queued(s.transport)
        manager.dispatcher.clock = lambda: self.t_s
        self._handle = manager.client.on_message

        def arrived(client, userdata, message):
            if message.topic not in manager._topics:
                return
            with self._lock:
                self._arrived.append((client, userdata, message))

        manager.client.on_message = arrived

    def _stamp(self, payload: bytes) -> None:
        import json

        try:
            self.t_s = sim_seconds(json.loads(payload)["timestamp"])
        except (ValueError, KeyError, TypeError):
            pass

    def _count_published(self, transport) -> None:
        publish = transport.publish

        def counted(subtopic, msg, *args, **kwargs):
            if subtopic in SUBSCRIBED:
                with self._lock:
                    self._published += 1
            return publish(subtopic, msg, *args, **kwargs)

        transport.publish = counted

    def _count_queued(self, transport) -> None:
        receive = transport._on_message

        def counted(subtopic, payload):
            receive(subtopic, payload)
            with self._lock:
                self._queued += 1

        transport._on_message = counted

    def _wait(self, done, what: str) -> None:
        deadline = time.monotonic() + WAIT_S
        while True:
            with self._lock:
                if done():
                    return
            if time.monotonic() > deadline:
                raise RuntimeError(f"the broker lost messages: {what}")
            time.sleep(0.0002)

    def settle(self) -> None:
        """Wait for every vehicle's message, hand them to the manager (by serial number, each
        vehicle's in order), wait until its answers are queued on the vehicles (RuntimeError
        after :data:`WAIT_S`)."""
        self._wait(
            lambda: self._handled + len(self._arrived) >= self._published,
            "the vehicles' messages did not all reach the fleet manager",
        )
        with self._lock:
            batch, self._arrived = self._arrived, []
        topics = self.manager._topics
        for client, userdata, message in sorted(batch, key=lambda m: topics[m[2].topic][0]):
            self._stamp(message.payload)
            self._handle(client, userdata, message)
            self._handled += 1
        self._wait(
            lambda: self._queued >= sum(self.manager.sent.values()),
            "the fleet manager's orders did not all reach the vehicles",
        )

    def flush(self, t_us: int) -> None:
        """The tick at ``t_us``: :meth:`settle`, ``on_tick`` (it may submit jobs), again
        :meth:`settle`."""
        self.settle()
        self.t_s = round(t_us * 1e-6, 3)
        self.on_tick(self.t_s)
        self.settle()

    def close(self) -> None:
        return None


def quiet(sessions: list, manager) -> None:
    """Wait until ``manager`` knows every session's vehicle online and each vehicle has received
    what the manager sent it (RuntimeError after :data:`WAIT_S`)."""
    deadline = time.monotonic() + WAIT_S
    while True:
        with manager._lock:
            online = all(
                manager.dispatcher.vehicles.get(s.serial) is not None
                and manager.dispatcher.vehicles[s.serial].online
                for s in sessions
            )
            sent = sum(manager.sent.values())
        if online and sum(s.transport.messages_in for s in sessions) >= sent:
            return
        if time.monotonic() > deadline:
            raise RuntimeError("the fleet manager did not see the vehicles online")
        time.sleep(0.001)
