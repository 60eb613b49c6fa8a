"""nav2's recoveries: they do what they say, and refuse to hit what the costmap holds."""

import math

import numpy as np

from amr_twin.navigation.costmap import Costmap
from amr_twin.navigation.footprint import Footprint
from amr_twin.navigation.kinematics import Limits
from amr_twin.navigation.progress import ProgressChecker
from amr_twin.navigation.recoveries import BackUp, ClearCostmaps, Spin, Wait

from nav_grids import room

FP = Footprint(-0.35, 0.35, 0.265)


def _run(rec, pose, dt=0.05, t_max=30.0):
    """Integrate the recovery's twists (a unicycle); return the final pose, the last step and the
    time."""
    pose, v, w, t = np.array(pose, float), 0.0, 0.0, 0.0
    rec.start(0.0, pose)
    while t < t_max:
        step = rec.step(t, pose, (v, w))
        if step.done:
            return pose, step, t
        v, w = step.v_m_s, step.w_rad_s
        pose += [v * math.cos(pose[2]) * dt, v * math.sin(pose[2]) * dt, w * dt]
        t += dt
    raise AssertionError("the recovery never ended")


def _costmap(walls=()):
    return Costmap(room(walls=walls), 0.265, 1.0, 3.0)


def test_spin_turns_a_quarter_turn_in_the_open_and_refuses_beside_a_wall():
    pose, step, _ = _run(Spin(_costmap(), FP, Limits(), 0.05), (6.0, 4.0, 0.0))
    assert (
        not step.failed and abs(pose[2] - math.pi / 2) < 0.08 and np.allclose(pose[:2], (6.0, 4.0))
    )
    tight = _costmap(
        walls=[(5.0, 4.32, 7.0, 5.0)]
    )  # a wall 0.05 m beside the left side: turning sweeps a corner into it
    pose, step, _ = _run(Spin(tight, FP, Limits(), 0.05), (6.0, 4.0, 0.0))
    assert step.failed and abs(pose[2]) < 0.2


def test_back_up_reverses_0_3_m_unless_something_is_behind():
    pose, step, _ = _run(BackUp(_costmap(), FP, Limits(), 0.05), (6.0, 4.0, 0.0))
    assert not step.failed and 0.3 <= 6.0 - pose[0] < 0.36
    blocked = _costmap(walls=[(5.4, 3.0, 5.5, 5.0)])  # a wall 0.25 m behind the rear
    pose, step, _ = _run(BackUp(blocked, FP, Limits(), 0.05), (6.0, 4.0, 0.0))
    assert step.failed and 6.0 - pose[0] < 0.1


def test_wait_and_clear():
    cm = _costmap()
    cm.marked[80, 120] = True
    _pose, step, t = _run(Wait(cm, FP, Limits(), 0.05), (6.0, 4.0, 0.0))
    assert 5.0 <= t < 5.1 and cm.marked.any()
    _run(ClearCostmaps(cm, FP, Limits(), 0.05), (6.0, 4.0, 0.0))
    assert not cm.marked.any()


def test_the_progress_checker_fails_after_10_s_within_0_5_m():
    pc = ProgressChecker(0.5, 10.0)
    assert all(
        pc.check(t, 0.04 * t, 0.0) for t in np.arange(0.0, 9.9, 0.5)
    )  # 0.4 m in 10 s: not yet 0.5 m
    assert not pc.check(10.5, 0.42, 0.0)
    assert pc.check(10.6, 0.6, 0.0)  # moved on: a new reference
