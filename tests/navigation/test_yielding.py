"""The robot gives way to people: it does not stand in a walking person's predicted path (it drives on through
it when that clears it, backs off or steps aside when not), and it breaks a standoff with a person standing
ahead of it by backing off."""

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
    """A person 2.2 m to the robot's left walking at 1.3 m/s across its middle: standing there (what the
    monitor's approach model leaves it) they walk into it within 1.5 s; the command chosen keeps them clear
    of the footprint, the best of the ways tried."""
    y = _yielding()
    person = People(0.0, np.array([[0.0, 2.2]]), np.array([[0.0, -1.3]]))
    assert _least_gap(y, (0.0, 0.0), person) < 0.0
    cmd = y.command(0.0, (0.0, 0.0, 0.0), (0.0, 0.0), (0.3, 0.0), (0.0, 0.0), person, np.zeros((0, 2)))
    assert cmd is not None and cmd != (0.0, 0.0)
    gap = _least_gap(y, cmd, person)
    assert gap > 0.05
    assert all(gap >= min(_least_gap(y, c, person), NAV.monitor.people_stop_m + NAV.people.yielding.margin_m) - 1e-9
               for c in y._grid)


def test_the_way_out_keeps_clear_of_a_wall_the_scan_sees():
    """The same person, a wall 0.2 m behind the robot's rear: it does not back into the wall."""
    y = _yielding()
    person = People(0.0, np.array([[0.0, 1.6]]), np.array([[0.0, -1.3]]))
    wall = np.column_stack([np.full(41, FP.x_min_m - 0.2), np.linspace(-2.0, 2.0, 41)])
    cmd = y.command(0.0, (0.0, 0.0, 0.0), (0.0, 0.0), (0.3, 0.0), (0.0, 0.0), person, wall)
    assert cmd is not None and cmd[0] > 0.0                                  # through the lane, not back


def test_no_person_in_the_way_leaves_the_command_alone():
    y = _yielding()
    behind = People(0.0, np.array([[-3.0, 1.0]]), np.array([[-1.3, 0.0]]))  # walking away behind it
    assert y.command(0.0, (0.0, 0.0, 0.0), (0.3, 0.0), (0.3, 0.0), (0.3, 0.0), behind, np.zeros((0, 2))) is None
    nobody = People(0.0, np.zeros((0, 2)), np.zeros((0, 2)))
    assert y.command(0.0, (0.0, 0.0, 0.0), (0.3, 0.0), (0.3, 0.0), (0.3, 0.0), nobody, np.zeros((0, 2))) is None


def test_a_standoff_with_a_person_standing_ahead_is_broken_by_backing_off():
    """Face to face in a doorway, each waiting: the robot backs off after standoff_s, not before."""
    y = _yielding()
    s = NAV.people.yielding
    ahead = People(0.0, np.array([[FP.x_max_m + 0.25 + 0.3, 0.0]]), np.zeros((1, 2)))
    t, cmds = 0.0, []
    while t < s.standoff_s + 1.0:
        cmds.append((t, y.command(t, (0.0, 0.0, 0.0), (0.0, 0.0), (0.3, 0.0), (0.0, 0.0), ahead, np.zeros((0, 2)))))
        t += 0.05
    assert all(c is None for t, c in cmds if t < s.standoff_s - 0.05)
    backing = [c for t, c in cmds if c is not None]
    assert backing and all(c[0] < 0.0 for c in backing) and math.isclose(backing[0][0], LIM.min_v_m_s)


def test_a_person_who_stopped_for_the_robot_gets_their_lane_cleared_at_once():
    """A person walked at the robot and stopped 0.3 m from its front (they give way): standing still, their last
    walking velocity says where they go once it is out of the way. The robot leaves that lane at once (not after
    the standoff's 3 s), and not by backing straight along it, which never clears it."""
    y = _yielding()
    xy = np.array([[FP.x_max_m + 0.25 + 0.3, 0.0]])
    stopped = People(0.0, xy, np.zeros((1, 2)), np.array([[-1.3, 0.0]]))
    cmd = y.command(0.0, (0.0, 0.0, 0.0), (0.0, 0.0), (0.3, 0.0), (0.0, 0.0), stopped, np.zeros((0, 2)))
    assert cmd is not None and cmd[1] != 0.0
    lane = People(0.0, xy, np.array([[-1.3, 0.0]]))
    def lane_gap(c):
        return float(y._lane_gaps(y._rollout((0.0, 0.0, 0.0), (0.0, 0.0), np.array([c], float)), lane)[0])
    assert lane_gap(cmd) > lane_gap((0.0, 0.0)) + 0.05 and lane_gap(cmd) > lane_gap((LIM.min_v_m_s, 0.0)) + 0.05


def test_a_person_walking_at_the_robots_middle_is_worse_than_past_its_edge():
    """Head on at 1.3 m/s from 2 m: every way out is walked into within the horizon; the one they pass most off
    the robot's middle is taken (a gap that stopped at the footprint's edge made them all alike: none taken)."""
    y = _yielding()
    head_on = People(0.0, np.array([[2.0, 0.0]]), np.array([[-1.3, 0.0]]))
    assert max(_least_gap(y, c, head_on) for c in y._grid) < 0.0
    cmd = y.command(0.0, (0.0, 0.0, 0.0), (0.0, 0.0), (0.3, 0.0), (0.0, 0.0), head_on, np.zeros((0, 2)))
    assert cmd is not None and cmd[1] != 0.0
    assert _least_gap(y, cmd, head_on) > _least_gap(y, (0.0, 0.0), head_on) + 0.1


def test_the_robot_waits_before_passing_close_to_a_standing_person_then_passes():
    """Driving at 0.3 m/s, a person standing 1.2 m ahead and 0.7 m beside its way (as the experiment's crossing
    people wait): it stands for courtesy_s, then drives on; someone 2 m beside the way is passed without a stop."""
    y = _yielding()
    s = NAV.people.yielding
    beside = People(0.0, np.array([[1.2, 0.7]]), np.zeros((1, 2)), np.zeros((1, 2)))
    t, cmds = 0.0, []
    while t < s.courtesy_s + 1.0:
        cmds.append((t, y.command(t, (0.0, 0.0, 0.0), (0.3, 0.0), (0.3, 0.0), (0.3, 0.0), beside, np.zeros((0, 2)))))
        t += 0.05
    assert all(c == (0.0, 0.0) for t, c in cmds if t < s.courtesy_s - 0.05)
    assert all(c is None for t, c in cmds if t > s.courtesy_s + 0.05)
    far = People(0.0, np.array([[1.2, 2.0]]), np.zeros((1, 2)), np.zeros((1, 2)))
    assert _yielding().command(0.0, (0.0, 0.0, 0.0), (0.3, 0.0), (0.3, 0.0), (0.3, 0.0), far, np.zeros((0, 2))) is None
