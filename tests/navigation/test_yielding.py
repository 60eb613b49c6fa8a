"""The robot gives way to people: it does not stand in a walking person's predicted path (it drives
on through it when that clears it, backs off or steps aside when not), and it breaks a standoff with
a person standing ahead of it by backing off."""

import math

import numpy as np

from amr_twin.model.config import load_config
from amr_twin.navigation.footprint import robot_footprint
from amr_twin.navigation.kinematics import Limits
from amr_twin.navigation.people import People
from amr_twin.navigation.stack import make_yielding
from amr_twin.navigation.yielding import Yielding

CFG = load_config()
NAV = CFG.navigation
FP = robot_footprint(CFG)
LIM = Limits(**NAV.limits.model_dump())


def _yielding() -> Yielding:
    return make_yielding(FP, LIM, NAV, 0.05, NAV.people.yielding.model_dump())


def _least_gap(y: Yielding, cmd, people: People) -> float:
    """The least gap to the people of ``cmd`` rolled out from the origin at rest."""
    poses = y._rollout((0.0, 0.0, 0.0), (0.0, 0.0), np.array([cmd], float))
    return float(y._gaps(poses, people, 0.0).min())


def test_a_robot_about_to_stop_in_a_walking_persons_lane_gets_out_of_it():
    """A person 2.2 m to the robot's left walking at 1.3 m/s across its middle: standing there (what
    the monitor's approach model leaves it) they walk into it within 1.5 s; the command chosen keeps
    them clear of the footprint, the best of the ways tried."""
    y = _yielding()
    person = People(0.0, np.array([[0.0, 2.2]]), np.array([[0.0, -1.3]]))
    assert _least_gap(y, (0.0, 0.0), person) < 0.0
    cmd = y.command(
        0.0, (0.0, 0.0, 0.0), (0.0, 0.0), (0.3, 0.0), (0.0, 0.0), person, np.zeros((0, 2))
    )
    assert cmd is not None and cmd != (0.0, 0.0)
    gap = _least_gap(y, cmd, person)
    assert gap > 0.05
    assert all(
        gap
        >= min(_least_gap(y, c, person), NAV.monitor.people_stop_m + NAV.people.yielding.margin_m)
        - 1e-9
        for c in y._grid
    )


def test_the_way_out_keeps_clear_of_a_wall_the_scan_sees():
    """The same person, a wall 0.2 m behind the robot's rear: it does not back into the wall."""
    y = _yielding()
    person = People(0.0, np.array([[0.0, 1.6]]), np.array([[0.0, -1.3]]))
    wall = np.column_stack([np.full(41, FP.x_min_m - 0.2), np.linspace(-2.0, 2.0, 41)])
    cmd = y.command(0.0, (0.0, 0.0, 0.0), (0.0, 0.0), (0.3, 0.0), (0.0, 0.0), person, wall)
    assert cmd is not None and cmd[0] > 0.0  # through the lane, not back


def test_no_person_in_the_way_leaves_the_command_alone():
    y = _yielding()
    behind = People(0.0, np.array([[-3.0, 1.0]]), np.array([[-1.3, 0.0]]))  # walking away behind it
    assert (
        y.command(
            0.0, (0.0, 0.0, 0.0), (0.3, 0.0), (0.3, 0.0), (0.3, 0.0), behind, np.zeros((0, 2))
        )
        is None
    )
    nobody = People(0.0, np.zeros((0, 2)), np.zeros((0, 2)))
    assert (
        y.command(
            0.0, (0.0, 0.0, 0.0), (0.3, 0.0), (0.3, 0.0), (0.3, 0.0), nobody, np.zeros((0, 2))
        )
        is None
    )


def test_a_standoff_with_a_person_standing_ahead_is_broken_by_backing_off():
    """Face to face in a doorway, each waiting: the robot backs off after standoff_s, not before."""
    y = _yielding()
    s = NAV.people.yielding
    ahead = People(0.0, np.array([[FP.x_max_m + 0.25 + 0.3, 0.0]]), np.zeros((1, 2)))
    t, cmds = 0.0, []
    while t < s.standoff_s + 1.0:
        cmds.append(
            (
                t,
                y.command(
                    t, (0.0, 0.0, 0.0), (0.0, 0.0), (0.3, 0.0), (0.0, 0.0), ahead, np.zeros((0, 2))
                ),
            )
        )
        t += 0.05
    assert all(c is None for t, c in cmds if t < s.standoff_s - 0.05)
    backing = [c for t, c in cmds if c is not None]
    assert (
        backing and all(c[0] < 0.0 for c in backing) and math.isclose(backing[0][0], LIM.min_v_m_s)
    )


def test_a_person_who_stopped_for_the_robot_gets_their_lane_cleared_at_once():
    """A person walked at the robot and stopped 0.3 m from its front (they give way): standing
    still, their last walking velocity says where they go once it is out of the way. The robot
    leaves that lane at once (not after the standoff's 3 s), and not by backing straight along it,
    which never clears it."""
    y = _yielding()
    xy = np.array([[FP.x_max_m + 0.25 + 0.3, 0.0]])
    stopped = People(0.0, xy, np.zeros((1, 2)), np.array([[-1.3, 0.0]]))
    cmd = y.command(
        0.0, (0.0, 0.0, 0.0), (0.0, 0.0), (0.3, 0.0), (0.0, 0.0), stopped, np.zeros((0, 2))
    )
    assert cmd is not None and cmd[1] != 0.0
    lane = People(0.0, xy, np.array([[-1.3, 0.0]]))

    def lane_gap(c):
        return float(
            y._lane_gaps(y._rollout((0.0, 0.0, 0.0), (0.0, 0.0), np.array([c], float)), lane)[0]
        )

    assert (
        lane_gap(cmd) > lane_gap((0.0, 0.0)) + 0.05
        and lane_gap(cmd) > lane_gap((LIM.min_v_m_s, 0.0)) + 0.05
    )


def test_a_person_walking_at_the_robots_middle_is_worse_than_past_its_edge():
    """Head on at 1.3 m/s from 2 m: every way out is walked into within the horizon; the one they
    pass most off the robot's middle is taken (a gap that stopped at the footprint's edge made them
    all alike: none taken)."""
    y = _yielding()
    head_on = People(0.0, np.array([[2.0, 0.0]]), np.array([[-1.3, 0.0]]))
    assert max(_least_gap(y, c, head_on) for c in y._grid) < 0.0
    cmd = y.command(
        0.0, (0.0, 0.0, 0.0), (0.0, 0.0), (0.3, 0.0), (0.0, 0.0), head_on, np.zeros((0, 2))
    )
    assert cmd is not None and cmd[1] != 0.0
    assert _least_gap(y, cmd, head_on) > _least_gap(y, (0.0, 0.0), head_on) + 0.1


def _drive_past(
    person: People, speed_m_s: float, x0_m: float, t_end_s: float
) -> list[tuple[float, float, float]]:
    """Drive along +x from ``(x0_m, 0)`` at the controller's ``speed_m_s`` past ``person`` (the
    navigator's way: the command Yielding returns, ramped by the limits, is the next cycle's
    ``vel``); ``(t_s, x_m, v_m_s)`` each cycle."""
    y, dt = _yielding(), 0.05
    t, x, vel, out = 0.0, x0_m, (0.0, 0.0), []
    while t < t_end_s:
        wanted = LIM.ramp(speed_m_s, 0.0, *vel, dt)
        cmd = y.command(t, (x, 0.0, 0.0), vel, wanted, wanted, person, np.zeros((0, 2)))
        vel = wanted if cmd is None else LIM.ramp(*cmd, *vel, dt)
        x += vel[0] * dt
        out.append((t, x, vel[0]))
        t += dt
    return out


def _gap_m(x_m: float, person: People) -> float:
    return float(FP.distance_m(person.xy_m - np.array([x_m, 0.0]))[0]) - NAV.people.person_radius_m


def test_the_robot_waits_before_passing_close_to_a_standing_person_then_passes():
    """Driving at 0.3 m/s, a person standing 1.2 m ahead and 0.7 m beside its way (as the
    experiment's crossing people wait): it stands for courtesy_s, then drives on; someone 2 m beside
    the way is passed without a stop."""
    s = NAV.people.yielding
    beside = People(0.0, np.array([[1.2, 0.7]]), np.zeros((1, 2)), np.zeros((1, 2)))
    run = _drive_past(beside, 0.3, 0.0, s.courtesy_s + 3.0)
    stood = [t for t, x, v in run if v == 0.0]
    assert stood and stood[-1] - stood[0] >= s.courtesy_s - 0.1
    assert run[-1][2] == 0.3 and run[-1][1] > 0.5  # then it drives on past them
    far = People(0.0, np.array([[1.2, 2.0]]), np.zeros((1, 2)), np.zeros((1, 2)))
    assert (
        _yielding().command(
            0.0, (0.0, 0.0, 0.0), (0.3, 0.0), (0.3, 0.0), (0.3, 0.0), far, np.zeros((0, 2))
        )
        is None
    )


def test_the_wait_for_a_standing_person_is_kept_for_where_the_robot_would_pass_them():
    """Coming at 0.75 m/s from 4.5 m before a person standing 0.7 m beside its way: the robot drives
    on until its stopping distance reaches the courtesy line and stands there, near the line rather
    than metres before it, for courtesy_s counted from when it stands (a wait begun 2.5 s of driving
    away and timed from then ran out while the robot was still slowing down, and it passed them 0.75
    m off at 0.3 m/s: seed 0's episode 9)."""
    s = NAV.people.yielding
    beside = People(0.0, np.array([[4.5, 0.7]]), np.zeros((1, 2)), np.zeros((1, 2)))
    run = _drive_past(beside, 0.75, 0.0, 12.0)
    stood = [(t, x) for t, x, v in run if v == 0.0 and t > 0.1]
    assert stood, "it never stood"
    assert stood[-1][0] - stood[0][0] >= s.courtesy_s - 0.1
    assert s.courtesy_m - 0.15 <= _gap_m(stood[0][1], beside) <= s.courtesy_m + 0.1
    assert run[-1][1] > 4.5 + FP.x_max_m
