"""The fleet manager with two to four vehicles that follow its orders without physics (a node a
step, tests/fleet_manager/fake_vehicles.py) on seeded job streams in the warehouse: every job is
done, no two vehicles ever stand on one node or drive one edge, and the deadlocks met (two robots at
the two ends of an aisle, a robot boxed in a dead end) are broken."""

from __future__ import annotations

import pytest

from fake_vehicles import FakeVehicle
from roadmaps import warehouse

pytest.importorskip("mujoco")

FACTSHEET = {
    "protocolFeatures": {
        "agvActions": [{"actionType": t, "actionScopes": ["NODE"]} for t in ("pick", "drop")]
    }
}


def drive(vehicles: int, jobs: int, seed: int, steps: int = 600) -> tuple[int, list]:
    """Jobs done and the manager's events after ``steps`` steps (or once all are done)."""
    from amr_twin.fleet_manager.dispatcher import Dispatcher, ManagerOptions
    from amr_twin.fleet_manager.jobs import job_stream

    roadmap = warehouse()
    charging = roadmap.nodes_of("end")[0]
    d = Dispatcher(roadmap, ManagerOptions(charging_nodes=(charging,)))
    faces = roadmap.nodes_of("aisle")
    starts = faces[:: len(faces) // vehicles][:vehicles]
    fleet = {f"amr-{i + 1}": FakeVehicle(f"amr-{i + 1}", roadmap, s) for i, s in enumerate(starts)}

    def deliver(out):
        for serial, sub, msg in out:
            fleet[serial].receive(sub, msg)

    for serial, v in fleet.items():
        deliver(d.on_connection(serial, {"connectionState": "ONLINE"}))
        deliver(d.on_factsheet(serial, FACTSHEET))
        deliver(d.on_state(serial, v.state()))
    deliver(d.submit(job_stream(roadmap, jobs, seed, exclude={charging})))
    done = 0
    for _step in range(steps):
        moves = {}
        for serial, v in fleet.items():
            before = v.node
            v.step()
            if v.node != before:
                moves[serial] = frozenset((before, v.node))
            deliver(d.on_state(serial, v.state()))
        at = [v.node for v in fleet.values()]
        assert len(set(at)) == len(at), at  # no two on one node
        assert len(set(moves.values())) == len(moves), moves  # no two on one edge
        done = sum(e["event"] == "done" and e.get("task") == "job" for e in d.events)
        if done == jobs:
            break
    return done, d.events


@pytest.mark.parametrize(
    "vehicles, jobs, seed", [(2, 10, 0), (2, 10, 5), (3, 15, 1), (3, 15, 4), (4, 20, 2), (4, 20, 6)]
)
def test_every_job_is_done_without_two_vehicles_on_a_node_or_an_edge(vehicles, jobs, seed):
    done, events = drive(vehicles, jobs, seed)
    assert done == jobs, [e for e in events if e["event"] in ("deadlock", "failed")][-5:]
    deadlocks = [e for e in events if e["event"] == "deadlock"]
    assert deadlocks and all(e["rerouted"] for e in deadlocks)  # met, and each broken
