"""A stand-in for a VDA 5050 master control in the fleet tests: a paho client on the vehicle's
topics that sends orders and instant actions with their headers and checks every message it receives
against the official 2.0.0 JSON schemas (vda5050_schemas/)."""

from __future__ import annotations

import json
import time
from pathlib import Path

import jsonschema
import paho.mqtt.client as mqtt

SCHEMAS = Path(__file__).parent / "vda5050_schemas"
FILES = {
    "state": "state.schema",
    "visualization": "visualization.schema",
    "connection": "connection.schema",
    "order": "order.schema",
    "factsheet": "factsheet.json",
}
BASE = "uagv/v2/amr-twin/amr-1/"
VEHICLE_TOPICS = ("state", "visualization", "connection", "factsheet")


def validate(subtopic: str, msg: dict) -> None:
    """Raise jsonschema.ValidationError unless ``msg`` is a valid ``subtopic`` message. The 2.0.0
    factsheet schema keeps its objects' schemas beside ``properties``: each is checked on its own
    too."""
    schema = json.loads((SCHEMAS / FILES[subtopic]).read_text())
    jsonschema.Draft202012Validator(schema, format_checker=jsonschema.FormatChecker()).validate(msg)
    if subtopic == "factsheet":
        for key in schema["required"]:
            if isinstance(schema.get(key), dict) and "type" in schema[key]:
                jsonschema.Draft202012Validator(schema[key]).validate(msg[key])


class Master:
    """Connected to ``url``; ``received`` holds (subtopic, message) of every message of the
    vehicles ``vehicles`` (serial numbers), in order; it sends to amr-1."""

    def __init__(self, url: str, vehicles: tuple = ("amr-1",)):
        host, port = url.removeprefix("mqtt://").split(":")
        self.received: list[tuple[str, dict]] = []
        self._ids = {"order": 0, "instantActions": 0}
        self.client = mqtt.Client(
            mqtt.CallbackAPIVersion.VERSION2, client_id=f"master-{time.monotonic_ns()}"
        )
        self.client.on_message = lambda _c, _u, m: self.received.append(
            (m.topic.rsplit("/", 1)[1], json.loads(m.payload))
        )
        self.client.connect(host, int(port))
        self.client.loop_start()
        for serial in vehicles:
            self.client.subscribe(BASE.replace("amr-1", serial) + "#", qos=1)
        time.sleep(0.3)

    def send(self, subtopic: str, body: dict, header_id: int | None = None) -> dict:
        """Publish ``body`` with a header (``header_id`` None: the next one of the topic)."""
        n = self._ids[subtopic] if header_id is None else header_id
        self._ids[subtopic] = max(self._ids[subtopic], n) + 1
        msg = {
            "headerId": n,
            "timestamp": "2026-12-07T10:00:00.00Z",
            "version": "2.0.0",
            "manufacturer": "amr-twin",
            "serialNumber": "amr-1",
            **body,
        }
        self.client.publish(BASE + subtopic, json.dumps(msg), qos=1).wait_for_publish(5)
        return msg

    def of(self, subtopic: str) -> list[dict]:
        return [m for s, m in self.received if s == subtopic]

    def close(self) -> None:
        self.client.disconnect()
        self.client.loop_stop()


def node(
    node_id: str,
    seq: int,
    x: float,
    y: float,
    theta=None,
    released: bool = True,
    map_id: str = "warehouse",
    actions=(),
) -> dict:
    pos = {"x": x, "y": y, "mapId": map_id, **({} if theta is None else {"theta": theta})}
    return {
        "nodeId": node_id,
        "sequenceId": seq,
        "released": released,
        "nodePosition": pos,
        "actions": list(actions),
    }


def edge(edge_id: str, seq: int, start: str, end: str, released: bool = True) -> dict:
    return {
        "edgeId": edge_id,
        "sequenceId": seq,
        "released": released,
        "startNodeId": start,
        "endNodeId": end,
        "actions": [],
    }


def order(order_id: str, nodes: list, edges: list, update_id: int = 0) -> dict:
    return {"orderId": order_id, "orderUpdateId": update_id, "nodes": nodes, "edges": edges}


def action(action_id: str, action_type: str, **parameters) -> dict:
    """An action (blocking HARD) with ``parameters`` as its actionParameters."""
    out = {"actionId": action_id, "actionType": action_type, "blockingType": "HARD"}
    if parameters:
        out["actionParameters"] = [{"key": k, "value": v} for k, v in parameters.items()]
    return out


def instant(action_id: str, action_type: str, **parameters) -> dict:
    return {"actions": [action(action_id, action_type, **parameters)]}


def deliver(session, master, subtopic: str, body: dict, header_id: int | None = None) -> None:
    """Send and wait (wall time) until the vehicle's client has it; it acts at the twin's next
    tick."""
    n = session.vehicles[0].transport.messages_in
    master.send(subtopic, body, header_id)
    deadline = time.monotonic() + 10.0
    while session.vehicles[0].transport.messages_in == n:
        assert time.monotonic() < deadline, f"the vehicle never received the {subtopic} message"
        time.sleep(0.005)
    session.run(0.1)


def run_until(session, done, limit_s: float) -> None:
    t_end = session.world.t_s + limit_s
    while not done() and session.world.t_s < t_end:
        session.run(0.2)


def last_state(session) -> dict:
    return [m for _t, s, m in session.vehicles[0].adapter.log if s == "state"][-1]


def settle_and_check_schemas(session, master) -> None:
    time.sleep(0.3)  # the broker delivers what is in flight
    assert master.of("state") and master.of("visualization")
    for subtopic, msg in master.received:
        if subtopic in VEHICLE_TOPICS:
            validate(subtopic, msg)
