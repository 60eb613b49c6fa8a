"""One episode of the fleet experiment on the warehouse: the twin under the project's fleet manager
through the embedded broker, an order carried from a rack face to a dock, measured; the same seed
gives the same JSON; a heavier payload costs more energy on the same order."""

import json
import time
from dataclasses import replace

import pytest

from amr_twin.experiments.fleet.episode import run_episode
from amr_twin.experiments.fleet.result import EpisodePoint
from amr_twin.fleet_manager.dispatcher import Dispatcher
from amr_twin.model.config import load_config

HEAVY = EpisodePoint(1, (50.0, 50.0), 0, 280.0, 300.0)
"""Seed 0 at 300 orders an hour: the first order (pick in the one-way south aisle, about 63 m round
the south rack row from the start) arrives at 25.8 s and is dropped before 280 s."""


@pytest.fixture(scope="module")
def heavy():
    return run_episode(load_config(), HEAVY)


def _bytes(result) -> str:
    data = result.as_json()
    data.pop("wall_s"), data.pop("cpu_s")
    return json.dumps(data, sort_keys=True)


def test_an_order_is_picked_carried_and_dropped_and_measured(heavy):
    first = heavy.jobs[0]
    assert first.robot == "amr-1" and not first.failed and first.done_s is not None
    assert first.assigned_s == pytest.approx(first.arrival_s, abs=0.05)  # the robot was idle
    assert 40.0 < first.distance_m < 90.0 and first.energy_wh > 0.1 and first.charge_as > 10.0
    assert 0 < first.driving_wh < first.energy_wh
    assert heavy.lead_time_p50_s == pytest.approx(first.done_s - first.arrival_s, abs=1e-3)
    done = [j for j in heavy.jobs if j.done_s is not None]
    assert heavy.orders_per_hour == pytest.approx(len(done) * 3600 / 280.0, abs=1e-3)
    robot = heavy.robots[0]
    busy = min(280.0, max(j.done_s or 280.0 for j in heavy.jobs if j.assigned_s)) - first.assigned_s
    assert robot.utilisation == pytest.approx(busy / 280.0, abs=0.01)
    assert heavy.collisions == 0 and heavy.deadlocks == 0 and heavy.near_misses == []
    assert heavy.least_distance_m is None  # one robot: no pair
    xs = [p[1] for p in robot.track]
    assert len(robot.track) == 560 and max(xs) - min(xs) > 5.0  # it drove, sampled every 0.5 s


def test_a_heavier_payload_costs_more_energy_on_the_same_order(heavy):
    light = run_episode(load_config(), replace(HEAVY, payload_kg=(0.0, 0.0)))
    a, b = light.jobs[0], heavy.jobs[0]
    assert (a.job_id, a.payload_kg, b.payload_kg) == ("job-1", 0.1, 50.0)
    assert b.distance_m == pytest.approx(a.distance_m, rel=0.1)  # the same route
    assert b.charge_as > 1.05 * a.charge_as and b.energy_wh > 1.05 * a.energy_wh
    assert b.driving_wh > 1.2 * a.driving_wh  # standing draws the same, loaded or not


def test_the_same_seed_gives_the_same_json_even_with_a_slow_manager(monkeypatch):
    point = replace(HEAVY, duration_s=45.0)
    first = run_episode(load_config(), point)
    assert first.jobs[0].assigned_s is not None and first.robots[0].energy_wh > 0
    on_state = Dispatcher.on_state

    def slow(self, serial, msg):  # a loaded machine: the manager answers 30 ms late (wall time)
        time.sleep(0.03)
        return on_state(self, serial, msg)

    monkeypatch.setattr(Dispatcher, "on_state", slow)
    assert _bytes(first) == _bytes(run_episode(load_config(), point))
