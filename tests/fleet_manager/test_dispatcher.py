"""The fleet manager's decisions from VDA 5050 states alone (no broker): jobs to the nearest idle
vehicle, a waiting vehicle's release extended by an order update stitched at its last base node,
a deadlock broken by a detour, charging below the threshold, pick and drop only for vehicles whose
factsheet lists them."""

from __future__ import annotations

import pytest

from roadmaps import node_at, warehouse

pytest.importorskip("mujoco")

FACTSHEET = {
    "protocolFeatures": {
        "agvActions": [
            {"actionType": t, "actionScopes": ["NODE"]} for t in ("pick", "drop", "startCharging")
        ]
    }
}


def state(roadmap, node, order_id="", seq=0, charge=90.0, **extra) -> dict:
    """A vehicle's state standing at ``node`` (its order ``order_id`` done up to sequenceId
    ``seq``)."""
    x, y = roadmap.xy(node)
    return {
        "orderId": order_id,
        "lastNodeId": node,
        "lastNodeSequenceId": seq,
        "nodeStates": [],
        "edgeStates": [],
        "driving": False,
        "agvPosition": {"x": x, "y": y, "theta": 0.0, "mapId": "warehouse"},
        "batteryState": {"batteryCharge": charge},
        "actionStates": [],
        "errors": [],
        **extra,
    }


def fleet(starts: dict, factsheet=FACTSHEET, charging=()):
    from amr_twin.fleet_manager.dispatcher import Dispatcher, ManagerOptions

    roadmap = warehouse()
    d = Dispatcher(roadmap, ManagerOptions(charging_nodes=tuple(charging)))
    for serial, xy in starts.items():
        d.on_connection(serial, {"connectionState": "ONLINE"})
        d.on_factsheet(serial, factsheet)
        d.on_state(serial, state(roadmap, node_at(roadmap, *xy)))
    return roadmap, d


def orders(out, serial):
    return [m for s, sub, m in out if s == serial and sub == "order"]


def released(order) -> list[str]:
    return [n["nodeId"] for n in order["nodes"] if n["released"]]


def test_the_second_vehicle_waits_then_an_update_releases_its_way():
    from amr_twin.fleet_manager.jobs import Job

    roadmap, d = fleet({"amr-1": (-2.7, 0.0), "amr-2": (4.7, 0.0)})
    west, mid, east, far = (node_at(roadmap, x, 0.0) for x in (-2.7, -0.2, 2.2, 4.7))
    first = orders(d.submit([Job("j1", mid, east, 20.0)]), "amr-1")[0]
    assert released(first) == [west, mid, east]
    assert [a["actionType"] for n in first["nodes"] for a in n["actions"]] == ["pick", "drop"]
    second = orders(d.submit([Job("j2", east, west, 10.0)]), "amr-2")[0]
    assert released(second) == [far] and len(second["nodes"]) == 4  # the rest a horizon
    assert d.traffic.waiting == {"amr-2": {"amr-1"}}
    # amr-1 at the drop node, actions done: it is idle in amr-2's way and is sent off it
    done = state(roadmap, east, "j1", 4)
    done["actionStates"] = [
        {"actionId": f"j1-{k}", "actionType": k, "actionStatus": "FINISHED"}
        for k in ("pick", "drop")
    ]
    out = d.on_state("amr-1", done)
    park = orders(out, "amr-1")[0]
    assert park["nodes"][-1]["nodeId"] not in (east, mid, west) and not orders(out, "amr-2")
    # amr-1 passed amr-2's drop node on its way: amr-2's order is updated from its last base node
    seq = 2 * [n["nodeId"] for n in park["nodes"]].index(west)
    out = d.on_state("amr-1", state(roadmap, west, park["orderId"], seq, driving=True))
    assert not orders(out, "amr-2")  # amr-1 still holds the drop node
    end = park["nodes"][-1]
    out = d.on_state("amr-1", state(roadmap, end["nodeId"], park["orderId"], end["sequenceId"]))
    update = orders(out, "amr-2")[0]
    assert (update["orderId"], update["orderUpdateId"]) == ("j2", 1)
    assert (update["nodes"][0]["nodeId"], update["nodes"][0]["sequenceId"]) == (far, 0)
    assert released(update) == [far, east, mid, west] and not d.traffic.waiting


def test_a_deadlock_at_both_ends_of_the_aisle_is_broken_by_a_detour_and_reported():
    from amr_twin.fleet_manager.jobs import Job

    roadmap, d = fleet({"amr-1": (-5.1, 0.2), "amr-2": (7.1, -0.1)})
    west, east = node_at(roadmap, -5.1, 0.2), node_at(roadmap, 7.1, -0.1)
    beyond_east, beyond_west = node_at(roadmap, 7.4, -2.0), node_at(roadmap, -6.4, 1.0)
    # each picks where it stands and drops beyond the other's end of the aisle, both sent the
    # shortest way at once (the assignment would send the second round the first, parked)
    from amr_twin.fleet_manager.progress import Task

    for serial, job in (
        ("amr-1", Job("j1", west, beyond_east, 5.0)),
        ("amr-2", Job("j2", east, beyond_west, 5.0)),
    ):
        d.start(d.vehicles[serial], Task.job_task(job, None))
    out = d._decide()
    events = [e for e in d.events if e["event"] == "deadlock"]
    assert len(events) == 1 and sorted(events[0]["vehicles"]) == ["amr-1", "amr-2"]
    rerouted = events[0]["rerouted"]
    update = orders(out, rerouted)[-1]
    ys = [n["nodePosition"]["y"] for n in update["nodes"]]
    assert max(abs(y) for y in ys) > 4.0  # round a rack row, not through the central aisle
    assert d.traffic.deadlock() is None


def test_a_vehicle_low_on_battery_goes_to_charge_and_is_told_to_stop_at_the_upper_threshold():
    roadmap = warehouse()
    dock = roadmap.nodes_of("end")[0]
    roadmap, d = fleet({"amr-1": (-2.7, 0.0)}, charging=[dock])
    start = node_at(roadmap, -2.7, 0.0)
    order = orders(d.on_state("amr-1", state(roadmap, start, charge=15.0)), "amr-1")[0]
    last = order["nodes"][-1]
    assert last["nodeId"] == dock and [a["actionType"] for a in last["actions"]] == [
        "startCharging"
    ]
    charging = state(roadmap, dock, order["orderId"], last["sequenceId"], charge=50.0)
    start_id = last["actions"][0]["actionId"]
    charging["actionStates"] = [
        {"actionId": start_id, "actionType": "startCharging", "actionStatus": "FINISHED"}
    ]
    assert not d.on_state("amr-1", charging)  # charging, below 80 %
    charging["batteryState"]["batteryCharge"] = 80.0
    ((serial, sub, msg),) = d.on_state("amr-1", charging)
    assert sub == "instantActions" and msg["actions"][0]["actionType"] == "stopCharging"


def test_pick_and_drop_are_left_out_for_a_vehicle_whose_factsheet_lacks_them():
    from amr_twin.fleet_manager.jobs import Job

    roadmap, d = fleet({"amr-1": (-2.7, 0.0)}, factsheet={"protocolFeatures": {"agvActions": []}})
    mid, east = node_at(roadmap, -0.2, 0.0), node_at(roadmap, 2.2, 0.0)
    order = orders(d.submit([Job("j1", mid, east, 20.0)]), "amr-1")[0]
    assert all(n["actions"] == [] for n in order["nodes"])


def test_a_seeded_job_stream_is_the_same_for_the_same_seed_and_picks_at_rack_faces():
    from amr_twin.fleet_manager.jobs import job_stream

    roadmap = warehouse()
    jobs = job_stream(roadmap, 20, seed=3, exclude={roadmap.nodes_of("end")[0]})
    assert jobs == job_stream(roadmap, 20, seed=3, exclude={roadmap.nodes_of("end")[0]})
    assert jobs != job_stream(roadmap, 20, seed=4)
    assert {j.pick for j in jobs} <= set(roadmap.nodes_of("aisle"))
    assert {j.drop for j in jobs} <= set(roadmap.nodes_of("end")[1:])
    assert all(5.0 <= j.payload_kg <= 50.0 for j in jobs)


def test_with_pooled_docks_a_drop_goes_to_the_dock_with_the_shorter_queue():
    from amr_twin.fleet_manager.dispatcher import Dispatcher, ManagerOptions
    from amr_twin.fleet_manager.jobs import Job
    from roadmaps import warehouse_lanes

    roadmap = warehouse_lanes()
    charging, *docks = sorted(roadmap.nodes_of("end"), key=lambda n: roadmap.xy(n)[0])
    d = Dispatcher(roadmap, ManagerOptions(charging_nodes=(charging,), pool_docks=True))
    for serial, xy in (("amr-1", (-2.8, -2.4)), ("amr-2", (-0.2, -2.4))):  # two lay-bys
        d.on_connection(serial, {"connectionState": "ONLINE"})
        d.on_factsheet(serial, FACTSHEET)
        d.on_state(serial, state(roadmap, node_at(roadmap, *xy)))
    south_east = min(docks, key=lambda n: roadmap.xy(n)[1])
    pick = node_at(roadmap, 2.2, -2.4)
    d.submit([Job("j1", pick, south_east, 5.0), Job("j2", pick, south_east, 5.0)])
    drops = {v.task.job.drop for v in d.vehicles.values()}
    assert drops == set(docks)  # the second to the other dock: the first has one bound for it
