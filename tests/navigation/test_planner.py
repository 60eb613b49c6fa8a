"""The global planner: shortest route on the grid, replanning around a blocked corridor, one-line
refusals."""

import math

import numpy as np

from amr_twin.navigation.costmap import Costmap
from amr_twin.navigation.costmap import goal_problem
from amr_twin.navigation.planner import GlobalPlanner

from nav_grids import room, two_corridors


def _planner(static, **kw):
    cm = Costmap(static, inscribed_radius_m=0.265, inflation_radius_m=1.0, cost_scaling_per_m=3.0)
    return cm, GlobalPlanner(cm, turn_room_m=0.44, **kw)


def test_in_an_open_room_the_plan_is_the_straight_line():
    _cm, p = _planner(room())
    plan = p.plan(np.array([2.0, 2.0]), np.array([10.0, 6.0]), goal_yaw_rad=1.0)
    assert (
        plan.length_m == np.float64(plan.length_m) and abs(plan.length_m - math.hypot(8, 4)) < 0.02
    )
    assert abs(plan.poses[-1, 2] - 1.0) < 1e-12 and np.allclose(plan.poses[0, :2], [2.0, 2.0])
    assert np.hypot(*np.diff(plan.xy_m, axis=0).T).max() <= 0.05 + 1e-9


def test_a_blocked_corridor_leads_to_a_plan_through_the_other():
    cm, p = _planner(two_corridors())
    start, goal = np.array([1.0, 2.5]), np.array([11.0, 2.5])
    south = p.plan(start, goal)
    assert abs(np.median(south.xy_m[:, 1]) - 2.5) < 0.3  # through the south corridor (y 1.5 to 3.5)
    cm.marked[int(1.5 / 0.05) : int(3.5 / 0.05), int(6.0 / 0.05) : int(6.4 / 0.05)] = (
        True  # a pallet jack across it
    )
    cm._refresh(int(1.5 / 0.05), int(3.5 / 0.05), int(6.0 / 0.05), int(6.4 / 0.05))
    north = p.plan(start, goal)
    assert north is not None and north.length_m > south.length_m + 3.0
    assert (
        north.xy_m[:, 1] > 4.5
    ).any()  # round the middle wall, through the north corridor (y 4.5 to 6.5)
    assert (cm.distance_at(north.xy_m) > 0.265).all()


def test_a_goal_inside_a_wall_or_cut_off_is_refused_in_one_line():
    cm, p = _planner(
        room(walls=[(5.0, 0.0, 5.2, 8.0)])
    )  # a wall across the room: the east half is cut off
    assert "inside an obstacle" in goal_problem(cm, (5.1, 4.0))
    assert "closer than the robot's half width" in goal_problem(cm, (5.4, 4.0))
    assert "outside the map" in goal_problem(cm, (50.0, 4.0))
    assert goal_problem(cm, (8.0, 4.0)) == ""
    assert p.plan(np.array([2.0, 4.0]), np.array([8.0, 4.0])) is None
    assert "cut off" in p.last_error and "\n" not in p.last_error


def test_the_plan_keeps_to_the_middle_of_a_corridor():
    _cm, p = _planner(two_corridors())
    plan = p.plan(np.array([3.0, 2.5]), np.array([9.0, 2.5]))
    assert np.abs(plan.xy_m[:, 1] - 2.5).max() < 0.1  # 1 m from both walls all the way


def test_in_the_aisles_hall_the_plan_takes_the_shortest_route():
    """Between routes of as many grid moves, the one of fewest metres: diagonals cost sqrt 2. From
    the west cross aisle to the east block's second aisle the visibility graph's shortest path is
    34.1 m."""
    from amr_twin.model.config import load_config
    from amr_twin.navigation.footprint import robot_footprint
    from amr_twin.navigation.stack import make_costmap, true_map

    cfg = load_config()
    fp = robot_footprint(cfg)
    p = GlobalPlanner(
        make_costmap(true_map(cfg, "aisles"), fp, cfg.navigation),
        turn_room_m=fp.circumscribed_radius_m,
    )
    plan = p.plan(np.array([-23.5, 0.0]), np.array([10.0, -4.8]))
    assert 34.07 <= plan.length_m <= 1.05 * 34.07


def test_diagonal_moves_cost_their_length():
    """Through a gap behind a baffle (12.7 m) or over the end of a long wall (15.7 m): a search
    charging a diagonal move like a straight one (pyastar2d's) finds the second as short as the
    first and took it."""
    static = room(
        14.0, 12.0, walls=[(6.8, 0.0, 7.2, 1.0), (6.8, 2.6, 7.2, 7.0), (4.8, 0.0, 5.2, 4.0)]
    )
    _cm, p = _planner(static)
    plan = p.plan(np.array([2.0, 2.0]), np.array([12.0, 2.0]))
    assert plan.length_m < 13.0 and plan.xy_m[:, 1].max() < 5.0


def test_a_person_standing_in_the_way_is_kept_people_m_from_or_the_corridor_is_given_up():
    cm, p = _planner(two_corridors(), people_m=0.865)
    start, goal = np.array([1.0, 2.5]), np.array([11.0, 2.5])
    aside = p.plan(
        start, goal, people_xy_m=np.array([[6.0, 1.9]])
    )  # 0.4 m south of the south corridor's middle
    d = np.hypot(*(aside.xy_m - [6.0, 1.9]).T)
    assert (
        d.min() >= 0.865 - 0.05 and aside.xy_m[:, 1].max() < 3.5
    )  # past them, in the same corridor
    middle = p.plan(
        start, goal, people_xy_m=np.array([[6.0, 2.5]])
    )  # no room for 0.865 m: the north corridor
    assert middle.xy_m[:, 1].max() > 4.5


def test_a_path_is_free_until_an_obstacle_or_a_person_closes_it():
    """What the navigator asks before it keeps a plan: the south corridor's path is free; a pallet
    jack beside it that leaves the robot room (the second tier: the inscribed radius, 0.45 m more
    from the jack) keeps it free, one across it or a person standing on it does not."""
    cm, p = _planner(two_corridors(), unmapped_pad_m=0.45, people_m=0.865)
    south = p.plan(np.array([1.0, 2.5]), np.array([11.0, 2.5]))
    assert p.path_free(south.xy_m)
    path_y = float(np.interp(6.2, south.xy_m[:, 0], south.xy_m[:, 1]))
    edge = (
        path_y - 0.265 - 0.45 - 0.1
    )  # a jack's north face 0.1 m clear of the second tier's keep-out
    r0, r1 = int(1.5 / 0.05), int(edge / 0.05)
    cm.marked[r0:r1, int(6.0 / 0.05) : int(6.4 / 0.05)] = True
    cm._refresh(r0, r1, int(6.0 / 0.05), int(6.4 / 0.05))
    assert p.path_free(south.xy_m)
    assert not p.path_free(south.xy_m, np.array([[6.2, path_y]]))
    cm.marked[r0 : int(3.5 / 0.05), int(6.0 / 0.05) : int(6.4 / 0.05)] = True
    cm._refresh(r0, int(3.5 / 0.05), int(6.0 / 0.05), int(6.4 / 0.05))
    assert not p.path_free(south.xy_m)
