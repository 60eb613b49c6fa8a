"""The navigation experiment on generated halls: door trips drawn as said, the doorway's clearance,
the report."""

import math
import subprocess
from types import SimpleNamespace

import numpy as np
import pytest

from amr_twin.experiments.navigation import experiment as nv
from amr_twin.experiments.navigation import generated as ng
from amr_twin.experiments.navigation.episode_run import EpisodeRun
from amr_twin.model.config import load_config
from amr_twin.model.generated_world import hall

WORLD = "generated:2?door=0.9"  # a tuning hall


@pytest.fixture(scope="module")
def episodes():
    return nv.episodes(load_config(), WORLD, 16, seed=4)


def test_door_trips_cross_the_inner_wall_and_the_others_keep_to_one_side(episodes):
    from amr_twin.navigation.footprint import robot_footprint
    from amr_twin.navigation.stack import make_costmap, true_map

    cfg = load_config()
    assert nv.episodes(cfg, WORLD, 16, seed=4) == episodes
    assert [e.start for e in nv.episodes(cfg, WORLD, 4, seed=5)] != [e.start for e in episodes[:4]]
    h = hall(WORLD)
    costmap = make_costmap(true_map(cfg, WORLD), robot_footprint(cfg), cfg.navigation)
    trips = [e for e in episodes if e.doors]
    assert 4 <= len(trips) <= 12 and set(e.scenario for e in episodes) == {
        "clear",
        "person",
        "pallet_jack",
    }
    for e in episodes:
        ends = np.array([e.start[:2], e.goal[:2]])
        assert (costmap.static_distance_at(ends) >= 0.7 - 0.05).all()
        assert not ng._in_cage(h, ends).any()
        west = ends[:, 0] < h.west_x1_m
        assert bool(e.doors) == (west[0] != west[1])
        assert ng.MIN_APART_M <= math.dist(*ends) <= ng.MAX_APART_M
    none = nv.episodes(cfg, WORLD, 6, seed=4, people="none")
    assert {e.scenario for e in none} == {"clear"}


def test_a_pallet_jack_closing_the_doorway_makes_a_door_trip_impassable():
    from amr_twin.model.worlds import Obstacle

    cfg = load_config()
    door = hall(WORLD).doors[0]
    west, east = (door.x_m - 2.0, door.y_m, 0.0), (door.x_m + 2.0, door.y_m, 0.0)
    across = Obstacle("pallet_jack", door.x_m + 0.6, door.y_m, (1.6, 0.75, 1.3), math.pi / 2)
    aside = Obstacle("pallet_jack", door.x_m + 0.6, door.y_m + 2.5, (1.6, 0.75, 1.3), math.pi / 2)
    assert not ng._passable(cfg, WORLD, across, west, east)
    assert ng._passable(cfg, WORLD, aside, west, east)


def _through(door, offset_m):
    """A straight drive west to east through ``door``, ``offset_m`` north of its middle, 10 ms
    poses."""
    x = np.arange(door.x_m - 3.0, door.x_m + 3.0, 0.005)
    return np.column_stack([x, np.full_like(x, door.y_m + offset_m), np.zeros_like(x)])


def test_the_doorway_clearance_is_measured_to_each_jamb_from_the_true_footprint():
    from amr_twin.navigation.footprint import robot_footprint

    cfg = load_config()
    door = hall(WORLD).doors[0]
    half_width = robot_footprint(cfg).outline_xy_m(0.01)[:, 1].max()
    episode = SimpleNamespace(doors=(door.name,))
    for offset in (0.1, -0.05):
        row = ng.door_metrics(
            cfg, WORLD, episode, SimpleNamespace(pose_true=_through(door, offset))
        )
        gap = row["door_clearance"][door.name]
        assert row["doors_crossed"] == [door.name] and row["door_trip"]
        assert gap["south_m"] == pytest.approx(0.45 + offset - half_width, abs=0.01)
        assert gap["north_m"] == pytest.approx(0.45 - offset - half_width, abs=0.01)
    back = _through(door, 0.0)[::-1]
    back[:, 0] = np.minimum(back[:, 0], door.x_m - 0.5)  # up to the wall and back: not through
    row = ng.door_metrics(cfg, WORLD, SimpleNamespace(doors=()), SimpleNamespace(pose_true=back))
    assert row["doors_crossed"] == [] and row["door_clearance"] == {}


def _row(world, door_trip, success, gap=None):
    return {
        "world": world,
        "door_trip": door_trip,
        "success": success,
        "collisions": 0,
        "index": 0,
        "scenario": "clear",
        "status": "succeeded" if success else "failed",
        "reason": "" if success else "stuck",
        "collided_with": [],
        "final_error_true_m": 0.1 if success else 3.0,
        "door_clearance": {}
        if gap is None
        else {"door0": {"width_m": 0.9, "south_m": gap, "north_m": gap + 0.1}},
    }


def test_the_report_keeps_the_tuning_halls_apart_from_the_held_out_ones(tmp_path):
    from amr_twin.experiments.navigation.generated_report import report

    rows = [
        _row("generated:1", True, True, 0.12),
        _row("generated:1", False, True),
        _row("generated:9", True, False, 0.03),
        _row("generated:9", True, True, 0.2),
    ]
    groups = {"tuning": ["generated:1"], "held_out": ["generated:9"]}
    summary = {
        g: {
            "worlds": w,
            "episodes": {
                "true/all": {
                    "episodes": 2,
                    "success_rate": 0.5,
                    "travelled_over_optimal_median": 1.0,
                    "travelled_over_optimal_max": 1.0,
                    "min_clearance_m": 0.1,
                    "person_clearance_ge_0_3_share": None,
                    "person_crossings": 0,
                }
            },
            "doors": ng.door_summary([r for r in rows if r["world"] in w]),
        }
        for g, w in groups.items()
    }
    assert summary["held_out"]["doors"]["door_trips"] == {
        "episodes": 2,
        "success": 1,
        "collisions": 0,
        "door_passages": 2,
        "door_clearance_min_m": 0.03,
        "door_clearance_median_m": pytest.approx(0.115),
        "final_error_true_m_median": pytest.approx(1.55),
        "final_error_true_m_max": 3.0,
    }
    data = {
        "worlds": ["generated:1", "generated:9"],
        "groups": groups,
        "episodes": 2,
        "seed": 0,
        "people": "none",
        "localisation": "ekf",
        "controller": "mppi",
        "firmware": "improved",
        "optimal": "lower bound",
        "summary": summary,
        "by_world": {
            w: ng.door_summary([r for r in rows if r["world"] == w])
            for w in ("generated:1", "generated:9")
        },
        "rows": rows,
        "jobs": 1,
        "wall_s": 1.0,
        "cpu_s": 1.0,
    }
    report(data, tmp_path)
    text = (tmp_path / "report.md").read_text()
    assert (
        "Tuning halls (tuned on, not to be quoted as results): generated:1. Held-out halls: "
        "generated:9." in text
    )
    assert "| held-out | door trips | 2 | 1 of 2 (50 %) | 0 | 2 | 0.030 / 0.115 |" in text
    assert "| tuning | door trips | 1 | 1 of 1 (100 %) | 0 | 1 | 0.120 / 0.120 |" in text
    assert (
        "`generated:9` episode 0 (clear, door trip): failed: stuck; true final error 3.00 m; "
        "door0 0.9 m" in text
    )


@pytest.mark.parametrize(
    "args, line",
    [
        (["--generated-seeds", "3-x"], "--generated-seeds 3-x: expected A-B, A,B,C or none"),
        (["--generated-seeds", "3-4", "--door-m", "3"], "--door-m 3: must be in [0.6, 2] m"),
        (["--door-m", "0.9"], "--door-m: only with --generated-seeds"),
        (
            ["--generated-seeds", "3", "--maps", "true,slam"],
            "--maps true,slam: a generated hall has no mapping drive",
        ),
        (["--world", "generated:3?door=9"], "--world generated:3?door=9: expected generated:SEED"),
        (
            ["--generated-seeds", "3", "--people", "many"],
            "--people 'many': static, walking, crossing or none",
        ),
    ],
)
def test_bad_hall_options_are_refused_in_one_line_before_any_run(tmp_path, args, line):
    done = subprocess.run(
        ["amr-twin", "experiment", "navigation", "--out", str(tmp_path / "o"), *args],
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert (
        done.returncode == 2 and line in done.stderr and len(done.stderr.strip().splitlines()) == 1
    ), done.stderr
    assert not (tmp_path / "o").exists()


def test_the_people_cost_is_measured_on_the_same_episodes_without_them(episodes, tmp_path):
    """Each episode with a walking person runs again without them, the same start and goal; the
    extra time to the goal counts only the pairs both reached; an episode whose robot touched a
    person counts as such."""
    from amr_twin.experiments.navigation.generated_report import _people_lines

    items = [EpisodeRun(None, WORLD, e, "true", None) for e in episodes]
    bare = ng.without_people(items)
    walking = [it for it in items if it.episode.actor is not None]
    assert walking and len(bare) == len(walking)
    assert all(
        b.episode.actor is None
        and b.episode.scenario == ng.WITHOUT_PEOPLE
        and (b.episode.start, b.episode.goal, b.episode.index)
        == (w.episode.start, w.episode.goal, w.episode.index)
        for b, w in zip(bare, walking)
    )

    def row(i, t, ok=True, hit=()):
        return {
            "world": WORLD,
            "index": i,
            "time_s": t,
            "success": ok,
            "actor": {"kind": "person"},
            "collided_with": list(hit),
        }

    rows = [
        row(0, 30.0),
        row(1, 42.0),
        row(2, 50.0, False, ["person_0"]),
        {**row(3, 20.0), "actor": None},
    ]
    ref = [{**row(i, t), "actor": None} for i, t in ((0, 28.5), (1, 32.0), (2, 30.0))]
    p = ng.people_penalty(rows, ref)
    assert (
        p["person_episodes"],
        p["person_success"],
        p["person_contact_episodes"],
        p["pairs"],
    ) == (3, 2, 1, 2)
    assert p["extra_s_median"] == pytest.approx(5.75) and p["extra_s_max"] == pytest.approx(10.0)
    text = "\n".join(_people_lines({"people": "crossing", "summary": {"held_out": {"people": p}}}))
    assert "| held-out | 3 | 2 of 3 (67 %) | 1 | 2 | 5.8 | 10.0 |" in text
