"""People in the robot's way, the whole twin (scan, tracker, controller, monitor, Yielding, the
drive):

- a person who does not give way crosses the robot's aisle as it comes: no contact, and the robot is
never
  standing in the lane the person is about to sweep while they are within 2 m of it;
- a person who gives way meets the robot at a 0.9 m doorway from the other side: both get through,
neither
  waits 10 s (the deadlock of each waiting for the other is broken).

Each runs on two seeds (the twin's noise and the MPPI's samples)."""

import math

import numpy as np
import pytest

from amr_twin.model.actors import Actor
from amr_twin.model.config import load_config
from amr_twin.navigation.footprint import robot_footprint
from amr_twin.navigation.kinematics import to_map
from amr_twin.navigation.navigation_run import navigate
from amr_twin.navigation.stack import REST_S, NavigationOptions
from amr_twin.assembly.twin import TwinOptions

from nav_grids import room, write_map

CFG = load_config()
FP = robot_footprint(CFG)
STANDING_M_S = 0.05
"""The robot stands while its true speed is below this, m/s."""
LANE_HALF_M = 0.225
"""Half the width a person sweeps: their torso's 0.45 m across the heading (actors.person)."""
NEAR_M = 2.0
SEEDS = (0, 1)


def _speed_m_s(run) -> np.ndarray:
    """The robot's true speed on the recorder's grid, m/s."""
    d = np.hypot(*np.diff(run.pose_true[:, :2], axis=0).T) / np.diff(run.t_s)
    return np.r_[d, d[-1:]]


def _actor_at(run, t_s: np.ndarray) -> np.ndarray:
    """The (only) actor's position (n, 2) at ``t_s`` from ``actors/poses`` (10 Hz, the pose last
    published)."""
    t = np.array([p[0] for p in run.actor_poses])
    xy = np.array([p[1][0][:2] for p in run.actor_poses])
    return xy[np.clip(np.searchsorted(t, t_s, side="right") - 1, 0, len(t) - 1)]


# --- a person who does not give way crossing the robot's aisle
# ---------------------------------------------

AISLE_Y, LANE_X = 3.0, 7.0
"""A 16 x 6 m hall: the robot drives east along y = 3 m; the person crosses it at x = 7 m, north to
south."""
CROSS_FROM, CROSS_TO = (LANE_X, 5.6), (LANE_X, 0.4)
SET_OFF_S = 7.0
"""The person sets off this long after the robot does: its front (at 0.7 m/s) is then in the lane,
and the person, 2.6 m away, reaches it in 1.8 s. Without Yielding the collision monitor stops the
robot there and the person walks into it (both seeds); with it, it drives on through. At 6 s it is
0.4 m short of the lane at 0.73 m/s and can do neither (one seed of two at 6.5 s): that meeting is
left to the courtesy wait for a standing person near the way."""


def _crossing(seed: int, tmp_path, sets=()):
    cfg = load_config(sets=list(sets)) if sets else CFG
    world = write_map(tmp_path, "hall", room(16.0, 6.0))
    start, goal = (2.0, AISLE_Y, 0.0), (13.0, AISLE_Y, None)
    walker = Actor(
        "person", (CROSS_FROM, CROSS_TO), 1.3, start_s=REST_S + SET_OFF_S, stop_within_m=0.0
    )
    twin_options = TwinOptions(
        firmware="improved",
        world=str(world),
        start_xy_yaw=start,
        visuals=False,
        seed=seed,
        actors=(walker,),
    )
    return navigate(
        cfg, twin_options, NavigationOptions(goals=(goal,), localisation="ekf", seed=seed)
    )


def parked_in_lane_s(run) -> float:
    """Time (s) the robot stood with its true footprint in the part of the person's lane still ahead
    of them while they were within NEAR_M of the footprint."""
    person = _actor_at(run, run.t_s)
    outline = to_map(run.pose_true, FP.outline_xy_m(0.02))  # (n, k, 2)
    in_lane = np.abs(outline[..., 0] - LANE_X) <= LANE_HALF_M
    ahead = outline[..., 1] < person[:, None, 1]  # the person walks south
    near = (
        np.hypot(outline[..., 0] - person[:, None, 0], outline[..., 1] - person[:, None, 1]).min(1)
        <= NEAR_M
    )
    parked = (in_lane & ahead).any(1) & near & (_speed_m_s(run) < STANDING_M_S)
    return float(parked.sum() * np.median(np.diff(run.t_s)))


@pytest.fixture(scope="module", params=SEEDS)
def crossing(request, tmp_path_factory):
    return _crossing(request.param, tmp_path_factory.mktemp("crossing"))


def test_a_person_who_does_not_give_way_crosses_the_robots_aisle_without_contact(crossing):
    out = crossing.outcomes[0]
    assert crossing.collisions == [], crossing.collisions
    assert out.status == "succeeded", out.reason
    person = _actor_at(crossing, crossing.t_s)
    assert person[-1, 1] < AISLE_Y - 1.0  # the person got across


def test_the_robot_never_stands_in_the_crossing_persons_lane(crossing):
    assert parked_in_lane_s(crossing) == 0.0


# --- a person who gives way, met at a 0.9 m doorway from the other side
# -----------------------------------

WALL_X, DOOR_Y, DOOR_M, WALL_T = 8.0, 4.0, 0.9, 0.2


def door_hall():
    lo, hi = DOOR_Y - DOOR_M / 2, DOOR_Y + DOOR_M / 2
    return room(
        16.0,
        8.0,
        walls=[
            (WALL_X - WALL_T / 2, 0.0, WALL_X + WALL_T / 2, lo),
            (WALL_X - WALL_T / 2, hi, WALL_X + WALL_T / 2, 8.0),
        ],
    )


def _door_meeting(seed: int, tmp_path):
    world = write_map(tmp_path, "door", door_hall())
    start, goal = (4.5, DOOR_Y, 0.0), (12.0, DOOR_Y, None)
    # the person sets off 3.5 m east of the door as the robot comes within about 2 m of it from the
    # west
    walker = Actor(
        "person",
        ((WALL_X + 3.5, DOOR_Y), (WALL_X - 4.5, DOOR_Y)),
        1.3,
        start_s=REST_S + (WALL_X - 2.0 - start[0]) / 0.55,
        stop_within_m=0.6,
    )
    twin_options = TwinOptions(
        firmware="improved",
        world=str(world),
        start_xy_yaw=start,
        visuals=False,
        seed=seed,
        actors=(walker,),
    )
    return navigate(
        CFG, twin_options, NavigationOptions(goals=(goal,), localisation="ekf", seed=seed)
    )


def waits_s(run) -> tuple[float, float]:
    """Time (s) the robot and the person each stood within 3 m of the doorway while the person had
    not reached their end (the robot: before reaching its goal)."""
    dt = float(np.median(np.diff(run.t_s)))
    out = run.outcomes[0]
    t = np.array([p[0] for p in run.actor_poses])
    xy = np.array([p[1][0][:2] for p in run.actor_poses])
    moving = np.r_[np.hypot(*np.diff(xy, axis=0).T) > 1e-4, True]
    near_p = np.hypot(xy[:, 0] - WALL_X, xy[:, 1] - DOOR_Y) <= 3.0
    person = float(((~moving) & near_p & (xy[:, 0] > WALL_X - 4.4)).sum() * np.median(np.diff(t)))
    near_r = np.hypot(run.pose_true[:, 0] - WALL_X, run.pose_true[:, 1] - DOOR_Y) <= 3.0
    active = (run.t_s >= out.t_start_s) & (run.t_s <= out.t_end_s)
    robot = float((near_r & active & (_speed_m_s(run) < STANDING_M_S)).sum() * dt)
    return robot, person


@pytest.mark.parametrize("seed", SEEDS)
def test_a_robot_and_a_person_meeting_at_a_0_9_m_door_both_get_through_within_seconds(
    seed, tmp_path
):
    run = _door_meeting(seed, tmp_path)
    out = run.outcomes[0]
    assert out.status == "succeeded", out.reason
    assert run.collisions == [], run.collisions
    person_end = np.array(run.actor_poses[-1][1][0][:2])
    assert person_end[0] < WALL_X - 4.0  # through the door, at their end
    robot_wait, person_wait = waits_s(run)
    assert robot_wait < 10.0 and person_wait < 10.0, (robot_wait, person_wait)
    assert math.isfinite(out.t_end_s)
