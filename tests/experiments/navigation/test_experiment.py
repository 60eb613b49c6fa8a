"""The navigation experiment's episodes, its optimal length and its metrics (the closed loops are in
tests/navigation)."""

import math

import numpy as np
import pytest

from amr_twin.experiments.navigation import experiment as nv
from amr_twin.experiments.navigation.episodes import CROSS_HALF_M
from amr_twin.experiments.navigation.metrics import _sign_changes, summary
from amr_twin.experiments.navigation.optimal import VisibilityGraph
from amr_twin.model.config import load_config
from amr_twin.model.world_geometry import Footprints


@pytest.fixture(scope="module")
def episodes():
    return nv.episodes(load_config(), "aisles", 16, seed=7)


def test_episodes_are_seeded_apart_and_placed_as_the_docstring_says(episodes):
    again = nv.episodes(load_config(), "aisles", 16, seed=7)
    assert again == episodes
    other = nv.episodes(load_config(), "aisles", 4, seed=8)
    assert [e.start for e in other] != [e.start for e in episodes[:4]]
    for e in episodes:
        apart = math.hypot(e.goal[0] - e.start[0], e.goal[1] - e.start[1])
        assert nv.MIN_APART_M <= apart <= nv.MAX_APART_M
        if e.scenario == "clear":
            assert e.obstacle is None and e.actor is None
        elif e.scenario == "person":  # walking (the default): an actor crossing, on no map
            assert e.obstacle is None and e.actor.kind == "person" and e.actor.speed_m_s == 1.3
            (ax, ay), (bx, by) = e.actor.waypoints_xy_m
            assert math.hypot(bx - ax, by - ay) == pytest.approx(2 * CROSS_HALF_M)
            for end in (e.start, e.goal):
                assert math.hypot((ax + bx) / 2 - end[0], (ay + by) / 2 - end[1]) > 3.0
        else:
            ob = e.obstacle
            assert ob.name == e.scenario and e.actor is None
            for end in (e.start, e.goal):
                assert math.hypot(ob.x_m - end[0], ob.y_m - end[1]) > 3.0
    assert {e.scenario for e in episodes} == set(nv.SCENARIOS)


def _box(cx, cy, hx, hy):
    return Footprints(np.array([[cx, cy]]), np.array([[hx, hy]]), np.zeros(1), ("box",))


def test_the_visibility_graph_finds_the_shortest_way_round_a_box():
    vg = VisibilityGraph(_box(5.0, 0.0, 1.0, 1.0), 0.002, (-5.0, -5.0, 15.0, 5.0))
    expected = (
        2 * math.hypot(4.0, 1.0) + 2.0
    )  # (0,0) -> (4,1) -> (6,1) -> (10,0): round a corner of the box
    assert vg.length_m((0.0, 0.0), (10.0, 0.0)) == pytest.approx(expected, abs=0.01)
    assert vg.length_m((0.0, 2.0), (10.0, 2.0)) == pytest.approx(10.0, abs=1e-9)  # a clear line
    assert vg.length_m((0.0, 0.0), (5.0, 0.0)) == math.inf  # a goal inside the box


def test_the_optimal_length_is_no_longer_than_the_planner_path():
    from amr_twin.navigation.costmap import Costmap
    from amr_twin.navigation.planner import GlobalPlanner
    from amr_twin.navigation.static_map import StaticMap, rasterise

    box = _box(5.0, 0.0, 1.0, 2.5)
    occ = rasterise(box, 0.05, (-5.0, -5.0), (200, 400))
    occ[:2], occ[-2:], occ[:, :2], occ[:, -2:] = True, True, True, True
    cm = Costmap(StaticMap(occ, np.zeros_like(occ), 0.05, (-5.0, -5.0), "box"), 0.265, 1.0, 3.0)
    plan = GlobalPlanner(cm).plan(np.array([0.0, 0.0]), np.array([10.0, 0.0]))
    vg = VisibilityGraph(box, 0.265, (-4.9, -4.9, 14.9, 4.9)).length_m((0.0, 0.0), (10.0, 0.0))
    assert vg <= plan.length_m <= 1.1 * vg


def test_sign_changes_of_the_yaw_rate_ignore_the_deadband():
    assert _sign_changes(np.array([0.1, -0.1, 0.1, 0.01, -0.01, 0.1])) == 2
    assert _sign_changes(np.array([0.3, 0.2, 0.0, 0.1])) == 0


def test_the_summary_counts_success_collisions_and_people_clearance():
    row = {
        "map": "true",
        "scenario": "person",
        "success": True,
        "collisions": 0,
        "time_s": 10.0,
        "barn_score": 0.4,
        "travelled_over_optimal": 1.05,
        "min_clearance_m": 0.3,
        "min_person_m": 0.35,
        "plan_ms": [10.0],
        "controller_ms": [2.0],
        "recoveries": [],
        "travelled_m": 20.0,
        "w_sign_changes_last_m": 1,
    }
    rows = [
        row,
        {**row, "success": False, "collisions": 1, "min_person_m": 0.2, "recoveries": ["spin"]},
        {**row, "scenario": "clear", "min_person_m": None},
    ]
    s = summary(rows)
    assert (
        s["true/all"]["success_rate"] == pytest.approx(2 / 3) and s["true/all"]["collisions"] == 1
    )
    assert (
        s["true/person"]["person_crossings"] == 2
        and s["true/person"]["person_clearance_ge_0_3_share"] == 0.5
    )
    assert s["true/all"]["recoveries_per_100m"] == pytest.approx(100 / 60)
