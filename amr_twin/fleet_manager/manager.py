"""The fleet manager on an MQTT broker: VDA 5050 2.0 only, so any vehicle of the standard can be
driven by it and it can be swapped for another master control.

It subscribes to ``<interface>/v2/<manufacturer>/+/state``, ``connection`` and ``factsheet`` of
the serial numbers it manages, hands each message to the
:class:`~amr_twin.fleet_manager.dispatcher.Dispatcher` (in paho's network thread, under a lock) and
publishes the orders and instant actions it returns (QoS 0, the specification's section 6.2).
"""

from __future__ import annotations

import json
from dataclasses import replace
import threading
import time

from amr_twin.fleet.protocol import MANUFACTURER, topic
from amr_twin.fleet.transport import broker_address
from amr_twin.fleet_manager.dispatcher import Dispatcher, ManagerOptions
from amr_twin.fleet_manager.jobs import Job

SUBSCRIBED = ("state", "connection", "factsheet")


class FleetManager:
    """The master control of vehicles ``serials`` on ``roadmap``, on the broker at ``url``;
    :meth:`submit` jobs, :meth:`summary`, :meth:`close`."""

    def __init__(
        self,
        url: str,
        roadmap,
        serials: list[str],
        interface: str,
        options: ManagerOptions = ManagerOptions(),
        manufacturer: str = MANUFACTURER,
    ):
        import paho.mqtt.client as mqtt

        host, port = broker_address(url)
        self.interface, self.manufacturer, self.serials = interface, manufacturer, list(serials)
        self._t0 = time.monotonic()
        self.dispatcher = Dispatcher(roadmap, options, clock=lambda: time.monotonic() - self._t0)
        self._lock = threading.Lock()
        self.sent: dict[str, int] = {}
        self.log: list[tuple[str, str, dict]] = []
        """(serial number, subtopic, message) of every message sent."""
        self._topics = {
            topic(interface, s, sub, manufacturer): (s, sub) for s in serials for sub in SUBSCRIBED
        }
        self._connected = threading.Event()
        self.client = mqtt.Client(
            mqtt.CallbackAPIVersion.VERSION2,
            client_id=f"{interface}-{manufacturer}-master",
            protocol=mqtt.MQTTv311,
        )
        self.client.on_connect = self._connect_cb
        self.client.on_message = self._message_cb
        try:
            self.client.connect(host, port, keepalive=15)
        except OSError as exc:
            raise OSError(f"--vda5050 {url}: cannot connect ({exc.strerror or exc})") from None
        self.client.loop_start()
        if not self._connected.wait(10.0):
            self.client.loop_stop()
            raise OSError(f"--vda5050 {url}: the broker did not accept the fleet manager")

    def _connect_cb(self, client, _userdata, _flags, reason, _properties=None) -> None:
        if reason == 0:
            for name in self._topics:
                client.subscribe(name, qos=1)
            self._connected.set()

    def _message_cb(self, _client, _userdata, message) -> None:
        found = self._topics.get(message.topic)
        if found is None:
            return
        serial, sub = found
        try:
            msg = json.loads(message.payload)
        except ValueError:
            return
        if not isinstance(msg, dict):
            return
        handler = {
            "state": self.dispatcher.on_state,
            "connection": self.dispatcher.on_connection,
            "factsheet": self.dispatcher.on_factsheet,
        }[sub]
        with self._lock:
            self._publish(handler(serial, msg))

    def _publish(self, out: list) -> None:
        for serial, sub, msg in out:
            self.log.append((serial, sub, msg))
            self.sent[sub] = self.sent.get(sub, 0) + 1
            self.client.publish(
                topic(self.interface, serial, sub, self.manufacturer), json.dumps(msg), qos=0
            )

    def submit(self, jobs: list[Job]) -> None:
        """Queue ``jobs`` (first come, first served)."""
        with self._lock:
            self._publish(self.dispatcher.submit(list(jobs)))

    def jobs_left(self) -> int:
        """Jobs not yet finished or failed (queued or being carried)."""
        with self._lock:
            busy = sum(v.task is not None and v.task.kind == "job" for v in self._vehicles())
            return len(self.dispatcher.pending) + busy

    def _vehicles(self):
        return self.dispatcher.vehicles.values()

    def summary(self) -> dict:
        """What the manager did: the roadmap's size, messages sent by topic, the events (placed,
        assigned, wait, deadlock, done, failed, ...) with their time since the start, s."""
        with self._lock:
            events = list(self.dispatcher.events)
            graph = self.dispatcher.roadmap.graph
            return {
                "vehicles": self.serials,
                "roadmap": {"nodes": graph.number_of_nodes(), "edges": graph.number_of_edges()},
                "messages_sent": dict(self.sent),
                "jobs_done": sum(e["event"] == "done" and e.get("task") == "job" for e in events),
                "jobs_failed": sum(e["event"] == "failed" and bool(e.get("job")) for e in events),
                "deadlocks": [e for e in events if e["event"] == "deadlock"],
                "events": events,
            }

    def close(self) -> None:
        self.client.disconnect()
        self.client.loop_stop()


def start_manager(
    cfg,
    world: str,
    url: str,
    serials: list[str],
    interface: str,
    jobs: int,
    seed: int,
    options: ManagerOptions = ManagerOptions(),
    start_xy: tuple[float, float] | None = None,
) -> FleetManager:
    """The manager of ``serials`` on ``world``'s roadmap with ``jobs`` seeded jobs queued
    (:func:`~amr_twin.fleet_manager.jobs.job_stream`); without charging nodes in ``options``, the
    dock nearest ``start_xy`` (the world's start) charges; on a roadmap with lanes the docks are
    pooled (a drop goes to the dock with the shortest queue)."""
    from amr_twin.fleet_manager.jobs import job_stream
    from amr_twin.fleet_manager.roadmap import world_roadmap
    from amr_twin.model.worlds import default_start

    roadmap = world_roadmap(cfg, world)
    options = replace(options, pool_docks=roadmap.graph.is_directed())
    if not options.charging_nodes:
        x, y = start_xy if start_xy is not None else default_start(world)[:2]
        dock = roadmap.nearest_of("end", x, y)
        options = replace(options, charging_nodes=(dock,) if dock else ())
    manager = FleetManager(url, roadmap, serials, interface, options)
    manager.submit(job_stream(roadmap, jobs, seed, exclude=set(options.charging_nodes)))
    return manager
