"""The collision monitor: a person stepping in ahead is stopped short of, the racks beside are
not."""

import math

import numpy as np

from amr_twin.navigation.collision_monitor import CollisionMonitor
from amr_twin.navigation.footprint import Footprint
from amr_twin.navigation.kinematics import Limits

FP = Footprint(-0.35, 0.35, 0.265)


def _person(x, y, r=0.2, n=12):
    a = np.linspace(0, 2 * np.pi, n, endpoint=False)
    return np.column_stack([x + r * np.cos(a), y + r * np.sin(a)])


def test_a_person_stepping_into_the_path_2_m_ahead_is_stopped_short_of_by_0_3_m():
    """Driving at the top speed, a person appears 2 m ahead of the front (a scan's worth late): the
    monitor's commands, through the drive's ramps at 20 Hz, stop the robot 0.3 m or more from
    them."""
    lim, mon = Limits(), CollisionMonitor(FP, 0.8)
    x, v, dt = 0.0, 0.8, 0.05
    person_x = FP.x_max_m + 2.0 + 0.2  # the person's near side 2 m ahead of the front
    for k in range(200):
        pts = _person(person_x - x, 0.0)  # in base_link
        want = mon.filter(0.8, 0.0, pts, np.ones(len(pts), bool))[0]
        v, _ = lim.ramp(want, 0.0, v, 0.0, dt)
        v = max(v, 0.0)
        x += v * dt
    gap = person_x - 0.2 - (x + FP.x_max_m)
    assert v == 0.0 and 0.3 <= gap < 1.0, (v, gap)
    assert mon.actions["approach"] > 0


def test_racks_beside_the_robot_do_not_slow_it():
    mon = CollisionMonitor(FP, 0.8)
    rack = np.column_stack(
        [np.linspace(-3, 3, 60), np.full(60, 0.7)]
    )  # a rack face 0.43 m from the side
    assert mon.filter(0.8, 0.0, rack, np.zeros(60, bool)) == (0.8, 0.0)
    assert (
        mon.filter(0.8, 0.0, rack, np.ones(60, bool))[0] < 0.8
    )  # were it unmapped (people): slowed


def test_a_return_inside_the_zone_stops_the_robot_unless_it_backs_away():
    mon = CollisionMonitor(FP, 0.8)
    pts = _person(0.6, 0.0)  # 0.05 m in front of the bumper
    assert mon.filter(0.3, 0.0, pts, np.ones(len(pts), bool)) == (0.0, 0.0)
    v, w = mon.filter(-0.1, 0.0, pts, np.ones(len(pts), bool))
    assert v < 0.0 and mon.actions["escape"] == 1


def test_a_turn_in_place_beside_an_unmapped_obstacle_is_allowed():
    mon = CollisionMonitor(FP, 0.8)
    jack = np.column_stack(
        [np.full(20, -1.0), np.linspace(-0.5, 0.5, 20)]
    )  # 0.65 m behind the rear
    v, w = mon.filter(0.0, 0.5, jack, np.ones(20, bool))
    assert w == 0.5 and math.isclose(v, 0.0)


def _people(xy, v):
    return np.array([xy], float), np.array([v], float)


def test_a_person_walking_at_the_robots_side_is_stopped_for_before_they_meet():
    """A person 1.2 m to the left and 0.9 m ahead walks across at 1.3 m/s: nothing is in the raw
    scan's zones yet, but the people zone, with the person walking on, scales the command."""
    mon = CollisionMonitor(FP, 0.8)
    no_scan = np.zeros((0, 2)), np.zeros(0, bool)
    v, _w = mon.filter(0.8, 0.0, *no_scan, people_base=_people((0.9, 1.2), (0.0, -1.3)))
    assert v < 0.3 and mon.actions["people_approach"] == 1
    v_away, _w = mon.filter(
        0.8, 0.0, *no_scan, people_base=_people((0.9, 1.2), (0.0, 1.3))
    )  # walking away
    assert (
        mon.actions["people_approach"] == 1 and v_away == 0.3
    )  # only the speed near people (0.3 m/s)
    assert mon.filter(0.8, 0.0, *no_scan, people_base=_people((-0.9, 1.2), (0.0, 1.3))) == (
        0.8,
        0.0,
    )  # behind


def test_a_standing_person_beside_is_passed_one_too_close_stops_the_robot_unless_it_moves_away():
    mon = CollisionMonitor(FP, 0.8)
    no_scan = np.zeros((0, 2)), np.zeros(0, bool)
    beside = _people(
        (-1.0, FP.half_width_m + 0.25 + 0.35), (0.0, 0.0)
    )  # behind the axle: 0.35 m from the disc
    assert mon.filter(0.5, 0.0, *no_scan, people_base=beside) == (0.5, 0.0)
    close = _people(
        (0.5, 0.6), (0.0, 0.0)
    )  # ahead on the left, 0.12 m from the disc: inside the 0.3 m zone
    assert mon.filter(0.5, 0.4, *no_scan, people_base=close) == (0.0, 0.0)  # towards them
    v, w = mon.filter(-0.2, 0.0, *no_scan, people_base=close)  # backing away: allowed
    assert v == -0.2 and mon.actions["people_escape"] == 1
    # a turn in place away from them (the disc's gap grows) is refused all the same: it swings the
    # corners
    assert mon.filter(0.0, -0.5, *no_scan, people_base=close) == (0.0, 0.0)
    assert mon.filter(0.0, 0.5, *no_scan, people_base=beside) == (0.0, 0.5)  # farther: turn freely
    # driving on away from one who walks up behind: at full speed (at the people speed towards them)
    behind = _people((-0.55, -0.45), (0.0, 1.3))
    assert mon.filter(0.6, 0.0, *no_scan, people_base=behind) == (0.6, 0.0)
    assert (
        mon.filter(0.6, 0.0, *no_scan, people_base=_people((0.55, -0.45), (1.3, 0.0)))[0] == 0.3
    )  # ahead, walking on


def test_the_people_gaps_of_all_steps_at_once_are_the_gaps_of_each_step():
    """The approach model's clearances to people walking on, all its steps at once, are those of the
    person gap at each step's pose (bit for bit: the monitor's decisions do not change), turning or
    not."""
    from amr_twin.navigation.kinematics import arc_poses

    mon, rng = CollisionMonitor(FP, 0.8), np.random.default_rng(4)
    for _ in range(20):
        xy, vel = (
            rng.uniform(-3.0, 3.0, (int(rng.integers(1, 5)), 2)),
            rng.uniform(-1.5, 1.5, (1, 2)),
        )
        vel = np.repeat(vel, len(xy), 0) + rng.uniform(-0.3, 0.3, xy.shape)
        v, w = float(rng.uniform(-0.8, 0.8)), float(rng.choice([0.0, rng.uniform(-1.5, 1.5)]))
        poses = arc_poses(0.0, 0.0, 0.0, v, w, mon.step_s, 40)
        t = mon.step_s * np.arange(1, 41)
        gaps = mon._people_gaps(xy, vel, t, poses)
        assert gaps.shape == (40, len(xy))
        for k in (0, 7, 39):
            assert np.array_equal(gaps[k], mon._person_gap(xy + t[k] * vel, *poses[k]))


def test_the_people_zone_grows_by_the_distance_the_drive_rolls_after_a_stop():
    """A person standing beside the path ahead, their disc 0.36 m from it: at 0.3 m/s the drive
    would roll 0.3 x 0.15 + 0.3^2 / 2 = 0.09 m after a stop, so the robot is slowed (the zone 0.39
    m); at 0.05 m/s (0.009 m) it drives on; with no lag and a hard brake the zone stays 0.3 m."""
    no_scan = np.zeros((0, 2)), np.zeros(0, bool)
    person = _people(
        (0.8, FP.half_width_m + 0.25 + 0.36), (0.0, 0.0)
    )  # the front passes it within 1.5 s
    mon = CollisionMonitor(FP, 0.8, decel_m_s2=1.0, people_stop_lag_s=0.15)
    assert mon.stopping_m(-0.3) == mon.stopping_m(0.3) == 0.3 * 0.15 + 0.09 / 2.0
    v, _w = mon.filter(0.3, 0.0, *no_scan, people_base=person)
    assert v < 0.3 and mon.actions["people_approach"] == 1
    assert mon.filter(0.05, 0.0, *no_scan, people_base=person) == (0.05, 0.0)
    hard = CollisionMonitor(FP, 0.8, decel_m_s2=100.0, people_stop_lag_s=0.0)
    assert hard.filter(0.3, 0.0, *no_scan, people_base=person) == (0.3, 0.0)
