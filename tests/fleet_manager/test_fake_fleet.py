"""The fleet manager with two to four vehicles that follow its orders without physics (a node a
step, tests/fleet_manager/fake_vehicles.py) on seeded job streams in the warehouse: every job is
done, no two vehicles ever stand on one node or drive one edge, and the deadlocks met (two robots at
the two ends of an aisle, a robot boxed in a dead end) are broken."""

from __future__ import annotations

import pytest

from fake_vehicles import drive
from roadmaps import warehouse

pytest.importorskip("mujoco")


@pytest.mark.parametrize(
    "vehicles, jobs, seed", [(2, 10, 0), (2, 10, 5), (3, 15, 1), (3, 15, 4), (4, 20, 2), (4, 20, 6)]
)
def test_every_job_is_done_without_two_vehicles_on_a_node_or_an_edge(vehicles, jobs, seed):
    done, _steps, events = drive(warehouse(), vehicles, jobs, seed)
    assert done == jobs, [e for e in events if e["event"] in ("deadlock", "failed")][-5:]
    deadlocks = [e for e in events if e["event"] == "deadlock"]
    assert deadlocks and all(e["rerouted"] for e in deadlocks)  # met, and each broken
