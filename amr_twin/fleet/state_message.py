"""The bodies of one vehicle's VDA 5050 2.0 ``state`` and ``visualization`` messages (the
specification's sections 6.10 and 6.11), built from its vehicle interface
(:class:`~amr_twin.fleet.vehicle.Vehicle`), its handling
(:class:`~amr_twin.fleet.handling.Handling`) and the order being driven."""

from __future__ import annotations

import math


def position(vehicle) -> dict:
    """The ``agvPosition`` (m, rad in [-pi, pi)); not initialised while the vehicle has no pose."""
    pose = vehicle.pose()
    if pose is None:
        return {
            "x": 0.0,
            "y": 0.0,
            "theta": 0.0,
            "mapId": vehicle.map_id,
            "positionInitialized": False,
        }
    return {
        "x": pose[0],
        "y": pose[1],
        "theta": float(((pose[2] + math.pi) % math.tau) - math.pi),
        "mapId": vehicle.map_id,
        "positionInitialized": True,
    }


def velocity(vehicle) -> dict:
    """The ``velocity`` (m/s, rad/s; a differential drive: vy 0)."""
    v, w = vehicle.velocity()
    return {"vx": v, "vy": 0.0, "omega": w}


def visualization(vehicle) -> dict:
    """The ``visualization`` body: position and velocity."""
    return {"agvPosition": position(vehicle), "velocity": velocity(vehicle)}


def information(station) -> list[dict]:
    """The ``information`` entries: the charging ``station`` the vehicle stands at (None: none)."""
    if station is None:
        return []
    return [
        {
            "infoType": "chargingStation",
            "infoLevel": "INFO",
            "infoDescription": f"at charging station {station.name}",
            "infoReferences": [{"referenceKey": "stationName", "referenceValue": station.name}],
        }
    ]


def state(
    vehicle,
    handling,
    order,
    last_node: tuple[str, int],
    nodes: list,
    edges: list,
    actions,
    errors: list[dict],
    *,
    driving: bool,
    paused: bool,
) -> dict:
    """The ``state`` body of ``vehicle`` driving ``order`` (None: none yet) with ``nodes`` and
    ``edges`` left, ``last_node`` (nodeId, sequenceId) traversed, ``actions``
    (:class:`~amr_twin.fleet.actions.ActionStates`) and ``errors`` (the state's entries)."""
    volt, soc = vehicle.battery()
    violated = vehicle.field_violated()
    return {
        "orderId": order.order_id if order else "",
        "orderUpdateId": order.update_id if order else 0,
        "lastNodeId": last_node[0],
        "lastNodeSequenceId": last_node[1],
        "nodeStates": [n.state() for n in nodes],
        "edgeStates": [e.state() for e in edges],
        "agvPosition": position(vehicle),
        "velocity": velocity(vehicle),
        "loads": handling.loads(),
        "driving": driving,
        "paused": paused,
        "newBaseRequest": bool(nodes) and not nodes[0].released,
        "actionStates": actions.messages(),
        "batteryState": {
            "batteryCharge": 100.0 * min(1.0, max(0.0, soc)),
            "batteryVoltage": volt,
            "charging": handling.charging,
        },
        "operatingMode": "AUTOMATIC",
        "errors": list(errors),
        "information": information(handling.station()),
        "safetyState": {
            "eStop": "MANUAL" if vehicle.estop_pressed() else "NONE",
            "fieldViolation": violated,
        },
    }
