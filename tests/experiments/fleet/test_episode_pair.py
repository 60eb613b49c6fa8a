"""Two robots in one warehouse (one physics) under the project's fleet manager: both take orders,
each measured on its own, no collision, no deadlock; the same seed gives the same JSON."""

import json

import pytest

from amr_twin.experiments.fleet.episode import run_episode
from amr_twin.experiments.fleet.result import EpisodePoint
from amr_twin.model.config import load_config

PAIR = EpisodePoint(2, (0.0, 30.0), 0, 280.0, 300.0)
"""Seed 0: job-1 arrives at 25.8 s, job-2 at 29.1 s, both picks in the one-way south aisle (about
30 m round the south rack row from the starts in the west) and both dropped before 280 s."""


@pytest.fixture(scope="module")
def pair():
    return run_episode(load_config(), PAIR)


def _bytes(result) -> str:
    data = result.as_json()
    data.pop("wall_s"), data.pop("cpu_s")
    return json.dumps(data, sort_keys=True)


def test_two_robots_each_take_an_order_and_are_measured_apart(pair):
    assert [r.serial for r in pair.robots] == ["amr-1", "amr-2"]
    first, second = pair.jobs[:2]
    assert {first.robot, second.robot} == {"amr-1", "amr-2"}  # the idle one nearest takes it
    assert first.done_s is not None and not first.failed and first.energy_wh > 0.1
    assert pair.orders_per_hour == pytest.approx(
        3600 / 280 * sum(j.done_s is not None and not j.failed for j in pair.jobs), abs=1e-3
    )
    for r in pair.robots:
        xs, ys = [p[1] for p in r.track], [p[2] for p in r.track]
        assert len(r.track) == 560 and max(xs) - min(xs) + max(ys) - min(ys) > 1.0  # both drove
        assert 0.3 < r.utilisation <= 1.0 and r.energy_wh > 0.3
    assert pair.robots[0].track[0][1:] != pair.robots[1].track[0][1:]
    assert pair.collisions == 0 and pair.deadlocks == 0
    assert pair.least_distance_m is not None and pair.least_distance_m > 1.0


def test_the_same_seed_gives_the_same_json_for_two_robots(pair):
    assert _bytes(pair) == _bytes(run_episode(load_config(), PAIR))
