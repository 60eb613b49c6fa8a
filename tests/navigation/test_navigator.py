"""The navigation stack closed round the twin: physics, LiDAR, firmware, the navigator on the bus.

Short episodes, each run once for the module: a goal behind the robot in a 2 m aisle, an aisle
blocked by an unmapped pallet jack, a person standing off the middle of a corridor, and episodes
on a warehouse map the code has never seen (generated here), imported as a ROS map world.
"""

import math

import mujoco
import numpy as np
import pytest

from amr_twin.experiments.navigation_metrics import footprint_clearance_m
from amr_twin.model.config import load_config
from amr_twin.model.worlds import Obstacle, load_map, wall_boxes, world_path
from amr_twin.navigation.footprint import robot_footprint
from amr_twin.navigation.stack import NavigationOptions, navigate, robot_top_m
from amr_twin.navigation.static_map import Boxes, obstacle_boxes, yaml_map
from amr_twin.sim.loop import TwinOptions

from nav_grids import random_warehouse, two_corridors, write_map

CFG = load_config()
FP = robot_footprint(CFG)


def _boxes(world, obstacles=()):
    """The world's obstacles (an MJCF world's geoms, a ROS map's extruded walls) and ``obstacles``, as boxes."""
    if str(world).endswith(".yaml"):
        walls = wall_boxes(load_map(world))
        b = Boxes(np.array([w[0][:2] for w in walls]), np.array([w[1][:2] for w in walls]),
                  np.array([w[2] for w in walls]), tuple(f"wall_{i}" for i in range(len(walls))))
    else:
        b = obstacle_boxes(mujoco.MjModel.from_xml_path(str(world_path(world))), 0.005, robot_top_m(CFG))
    extra = Boxes(np.array([[o.x_m, o.y_m] for o in obstacles]).reshape(-1, 2),
                  np.array([[o.size_m[0] / 2, o.size_m[1] / 2] for o in obstacles]).reshape(-1, 2),
                  np.array([o.yaw_rad for o in obstacles]), tuple(o.name for o in obstacles))
    return Boxes(np.vstack([b.centre_xy_m, extra.centre_xy_m]), np.vstack([b.half_xy_m, extra.half_xy_m]),
                 np.concatenate([b.yaw_rad, extra.yaw_rad]), b.names + extra.names)


def _go(world, start, goal, obstacles=(), localisation="truth", controller="mppi", map_yaml=None, seed=0):
    twin_options = TwinOptions(firmware="improved", world=str(world), start_xy_yaw=start, visuals=False,
                               obstacles=tuple(obstacles), seed=seed)
    return navigate(CFG, twin_options, NavigationOptions(goals=(goal,), localisation=localisation,
                                                         controller=controller, map_yaml=map_yaml, seed=seed))


@pytest.fixture(scope="module", params=["mppi", "rpp"])
def behind(request):
    """In the aisles world's 2 m aisle at y = -4.8, facing east; the goal 3 m behind, facing west."""
    return _go("aisles", (-10.0, -4.8, 0.0), (-13.0, -4.8, math.pi), controller=request.param)


def test_a_goal_behind_the_robot_in_a_2_m_aisle_is_reached_without_touching_a_rack(behind):
    out = behind.outcomes[0]
    assert out.status == "succeeded", out.reason
    assert behind.collisions == []
    x, y, yaw = behind.pose_true[-1]
    assert math.hypot(x + 13.0, y + 4.8) <= 0.25 and abs(math.remainder(yaw - math.pi, 2 * math.pi)) <= 0.25
    clearance = footprint_clearance_m(behind.pose_true[::10], FP, _boxes("aisles"))
    assert clearance.min() > 0.1  # the racks are 0.74 m from the sides in the middle of the aisle


@pytest.fixture(scope="module")
def corridors(tmp_path_factory):
    """A 12 x 8 m ROS map world (walls extruded) with two 2 m corridors round a middle wall."""
    return write_map(tmp_path_factory.mktemp("corridors"), "corridors", two_corridors())


@pytest.fixture(scope="module")
def blocked(corridors):
    jack = Obstacle("pallet_jack", 6.2, 2.5, (0.6, 1.95, 1.3))  # across the south corridor
    return _go(corridors, (1.0, 2.5, 0.0), (11.0, 2.5, 0.0), obstacles=[jack]), jack


def test_a_blocked_aisle_leads_to_a_replan_through_another(blocked, corridors):
    run, jack = blocked
    assert run.outcomes[0].status == "succeeded", run.outcomes[0].reason
    assert run.collisions == []
    went = run.pose_true[:, 1]
    assert went.max() > 4.8  # round the middle wall, through the north corridor (y = 4.5 to 6.5)
    assert footprint_clearance_m(run.pose_true[::10], FP, _boxes(corridors, [jack])).min() > 0.05  # 0.11 m: round the wall end
    assert len(run.outcomes[0].plan_cpu_s) >= 5  # replanned on the way, at 1 Hz


def test_a_person_off_the_middle_of_the_corridor_is_passed_0_3_m_or_more_away(corridors):
    person = Obstacle("person", 6.0, 2.0, (0.45, 0.3, 1.7))  # 0.5 m south of the corridor's middle
    run = _go(corridors, (1.0, 2.5, 0.0), (11.0, 2.5, 0.0), obstacles=[person])
    assert run.outcomes[0].status == "succeeded", run.outcomes[0].reason
    assert run.collisions == []
    assert footprint_clearance_m(run.pose_true[::5], FP, _boxes(corridors, [person])).min() >= 0.3


@pytest.fixture(scope="module")
def unseen(tmp_path_factory):
    """Two seeded start/goal pairs on a warehouse generated here, localised by the EKF (UWB anchors of the
    parameter file: the hall's corners), imported as a ROS map world."""
    folder = tmp_path_factory.mktemp("unseen")
    static = random_warehouse(11)
    path = write_map(folder, "unseen", static)
    rng = np.random.default_rng(3)
    free = np.argwhere(static.occupied == 0)
    from amr_twin.navigation.stack import make_costmap
    cm = make_costmap(yaml_map(path), FP)
    ok = cm.centres_xy_m(*np.nonzero(cm.static_dist_m >= 0.7))
    runs = []
    while len(runs) < 2:
        a, b = ok[rng.integers(len(ok))], ok[rng.integers(len(ok))]
        if not 8.0 <= math.hypot(*(b - a)) <= 14.0:
            continue
        start = (float(a[0]), float(a[1]), float(rng.uniform(-math.pi, math.pi)))
        goal = (float(b[0]), float(b[1]), float(rng.uniform(-math.pi, math.pi)))
        runs.append(_go(path, start, goal, localisation="ekf", seed=len(runs)))
    assert len(free) > 0
    return runs, path


def test_a_warehouse_the_code_has_never_seen_is_navigated(unseen):
    runs, path = unseen
    for run in runs:
        assert run.outcomes[0].status == "succeeded", run.outcomes[0].reason
        assert run.collisions == []
        assert footprint_clearance_m(run.pose_true[::10], FP, _boxes(path)).min() > 0.02  # 0.08 m turning at a goal 0.7 m from a wall
