"""The navigation experiment's spec checks its inputs from Python, without the CLI, in one line
naming the field."""

from pathlib import Path

import pytest

from amr_twin.experiments.catalogue import experiments
from amr_twin.experiments.navigation.spec import (
    EPISODE_SIM_S,
    MAX_EPISODES,
    NavigationSpec,
    hall_seeds,
)

ROOM_MAP = Path(__file__).resolve().parents[3] / "models" / "worlds" / "room_map.yaml"


def test_the_default_spec_runs_the_aisles_on_both_maps():
    plan = NavigationSpec().validate()
    assert plan.halls is None and plan.maps == ("true", "slam") and plan.places() == 2
    assert NavigationSpec(episodes=3).simulated_s(plan) == 3 * 2 * EPISODE_SIM_S


def test_generated_halls_run_on_their_true_map_apart_from_the_tuning_ones():
    plan = NavigationSpec(generated_seeds="3-5", tuning_seeds="4", door_m=0.9).validate()
    assert plan.maps == ("true",) and len(plan.halls) == 3 and plan.places() == 3
    assert plan.tuning == [h for h in plan.halls if h.startswith("generated:4")]
    assert hall_seeds("--tuning-seeds", "none") == [] and hall_seeds("--x", "2,7") == [2, 7]


@pytest.mark.parametrize(
    "spec, named",
    [
        (NavigationSpec(seed=-1), "--seed -1: must be a whole number in [0, 2^32)"),
        (NavigationSpec(seed=2**32), f"--seed {2**32}: must be a whole number"),
        (NavigationSpec(episodes=0), f"--episodes 0: must be in [1, {MAX_EPISODES}]"),
        (NavigationSpec(episodes=MAX_EPISODES + 1), f"--episodes {MAX_EPISODES + 1}: must be"),
        (NavigationSpec(maps="true,true"), "--maps 'true,true': true, slam or true,slam"),
        (NavigationSpec(maps="lidar"), "--maps 'lidar': true, slam or true,slam"),
        (NavigationSpec(people="many"), "--people 'many': static, walking, crossing or none"),
        (NavigationSpec(door_m=0.9), "--door-m: only with --generated-seeds"),
        (NavigationSpec(generated_seeds="3", door_m=3.0), "--door-m 3: must be in [0.6, 2] m"),
        (NavigationSpec(generated_seeds="3-x"), "--generated-seeds 3-x: expected A-B, A,B,C"),
        (NavigationSpec(generated_seeds="4-3"), "--generated-seeds 4-3: expected A-B, A,B,C"),
        (NavigationSpec(generated_seeds="3,3"), "--generated-seeds 3,3: expected A-B, A,B,C"),
        (
            NavigationSpec(generated_seeds="3", tuning_seeds="x"),
            "--tuning-seeds x: expected A-B, A,B,C",
        ),
        (NavigationSpec(generated_seeds="3", maps="slam"), "--maps slam: a generated hall has no"),
        (NavigationSpec(world="generated:3?door=9"), "--world generated:3?door=9: expected"),
        (NavigationSpec(controller="teb"), "--controller 'teb': must be one of"),
        (NavigationSpec(localisation="gps"), "--localisation 'gps': must be one of"),
        (NavigationSpec(world="nowhere"), "--world nowhere: not a world of models/worlds/"),
        (NavigationSpec(world=str(ROOM_MAP)), f"--world {ROOM_MAP}: a ROS map world has no"),
        (
            NavigationSpec(generated_seeds="3", slam_map=ROOM_MAP),
            "--slam-map: a generated hall runs on its true map only",
        ),
        (NavigationSpec(slam_map=Path("/nonexistent/m.yaml")), "--slam-map "),
        (NavigationSpec(world="empty"), "world empty: no mapping route"),
    ],
)
def test_each_bad_field_is_refused_in_one_line_naming_it(spec, named):
    with pytest.raises(ValueError) as refused:
        spec.validate()
    assert str(refused.value).startswith(named) and "\n" not in str(refused.value), refused.value


def test_a_ros_map_world_runs_on_its_true_map_or_a_given_slam_map():
    assert NavigationSpec(world=str(ROOM_MAP), maps="true").validate().maps == ("true",)
    plan = NavigationSpec(world=str(ROOM_MAP), slam_map=ROOM_MAP).validate()
    assert plan.maps == ("true", "slam")


def test_the_registry_holds_navigation_with_its_spec():
    assert experiments().get("navigation").spec is NavigationSpec
