"""The master control's VDA 5050 2.0 messages: orders (a released base and an unreleased horizon,
stitched updates) and instant actions, with their headers (the specification's sections 6.4, 6.6,
6.8 and 6.9).

A route's node ``i`` has sequenceId ``2 i`` and the edge after it ``2 i + 1`` for the whole order,
so that every update starts at the last base node with the sequenceId the vehicle already has
(section 6.6.2).
"""

from __future__ import annotations

from datetime import datetime, timezone

from amr_twin.fleet.protocol import MANUFACTURER, VERSION


class Headers:
    """Header ids counted per vehicle and topic from 0; timestamps from the wall clock (UTC)."""

    def __init__(self, manufacturer: str = MANUFACTURER):
        self.manufacturer = manufacturer
        self._ids: dict[tuple[str, str], int] = {}

    def header(self, serial: str, subtopic: str) -> dict:
        n = self._ids.get((serial, subtopic), 0)
        self._ids[serial, subtopic] = n + 1
        now = datetime.now(timezone.utc)
        return {
            "headerId": n,
            "timestamp": now.strftime("%Y-%m-%dT%H:%M:%S.") + f"{now.microsecond // 1000:03d}Z",
            "version": VERSION,
            "manufacturer": self.manufacturer,
            "serialNumber": serial,
        }


def action(action_id: str, action_type: str, parameters: dict | None = None) -> dict:
    """A HARD-blocking action; ``parameters`` as actionParameters (key, value)."""
    out = {"actionId": action_id, "actionType": action_type, "blockingType": "HARD"}
    if parameters:
        out["actionParameters"] = [{"key": k, "value": v} for k, v in parameters.items()]
    return out


def load_action(kind: str, job_id: str, node: str, payload_kg: float) -> dict:
    """A ``pick`` or ``drop`` node action with the parameters of the specification's table of
    predefined actions (lhd, stationType, stationName, loadType, loadId) and the load's weight, kg
    (the state's ``loads[].weight``)."""
    return action(
        f"{job_id}-{kind}",
        kind,
        {
            "lhd": "LHD1",
            "stationType": "floor",
            "stationName": node,
            "loadType": "box",
            "loadId": job_id,
            "weight": round(float(payload_kg), 3),
        },
    )


def order(
    headers: Headers,
    serial: str,
    order_id: str,
    update_id: int,
    route: list[str],
    first: int,
    held: int,
    actions: dict[int, list[dict]],
    position,
) -> dict:
    """The order (``update_id`` 0) or update of ``route`` from index ``first`` (the last base node
    of an update): nodes up to ``held`` released, the rest the horizon. ``actions``: route index ->
    node actions; ``position(node)``: its nodePosition."""
    nodes = [
        {
            "nodeId": route[i],
            "sequenceId": 2 * i,
            "released": i <= held,
            "nodePosition": position(route[i]),
            "actions": actions.get(i, []),
        }
        for i in range(first, len(route))
    ]
    edges = [
        {
            "edgeId": f"{route[i]}-{route[i + 1]}",
            "sequenceId": 2 * i + 1,
            "released": i + 1 <= held,
            "startNodeId": route[i],
            "endNodeId": route[i + 1],
            "actions": [],
        }
        for i in range(first, len(route) - 1)
    ]
    return {
        **headers.header(serial, "order"),
        "orderId": order_id,
        "orderUpdateId": update_id,
        "nodes": nodes,
        "edges": edges,
    }


def instant(headers: Headers, serial: str, actions: list[dict]) -> dict:
    """An instantActions message; each action names its type as ``actionType`` (the
    specification's text) and ``actionName`` (the 2.0.0 JSON schema's required field)."""
    named = [{**a, "actionName": a["actionType"]} for a in actions]
    return {**headers.header(serial, "instantActions"), "actions": named}
