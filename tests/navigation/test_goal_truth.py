"""Success judged by the truth: the navigator's estimate says reached, the twin's true pose says by
how much."""

import math
from types import SimpleNamespace

import numpy as np
import pytest

from amr_twin.model.config import load_config
from amr_twin.navigation.goal_truth import final_errors, judge
from amr_twin.navigation.navigator import GoalOutcome

GOAL = (-6.0, 0.0, math.pi)


@pytest.mark.parametrize(
    "true_pose, status, reason",
    [
        (
            (-6.29, 0.0, math.pi),
            "aborted",
            "reached by the estimate, true pose 0.290 m from the goal (tolerance 0.250 m)",
        ),
        (
            (-6.1, 0.0, math.pi - 0.4),
            "aborted",
            "reached by the estimate, true heading 23 deg off the goal's",
        ),
        ((-6.2, 0.1, math.pi - 0.2), "succeeded", ""),
    ],
)
def test_a_goal_the_estimate_reached_is_reached_only_if_the_truth_is_within_the_tolerances(
    true_pose, status, reason
):
    out = GoalOutcome(GOAL, status="succeeded")
    errors = final_errors(GOAL, true_pose, (-6.1, 0.0, math.pi))
    assert errors.estimate_xy_m == pytest.approx(0.1) and errors.estimate_yaw_rad == pytest.approx(
        0.0
    )
    judge(out, errors, 0.25, 0.25)
    assert out.status == status and out.reason.startswith(reason)


def test_a_goal_without_yaw_is_judged_on_position_and_other_outcomes_are_kept():
    errors = final_errors((1.0, 2.0, None), (1.0, 2.2, 3.0), None)
    assert (
        errors.true_yaw_rad is None and errors.estimate_xy_m is None and errors.within(0.25, 0.01)
    )
    aborted = GoalOutcome(GOAL, status="aborted", reason="timed out")
    judge(aborted, final_errors(GOAL, (0.0, 0.0, 0.0)), 0.25, 0.25)
    assert (aborted.status, aborted.reason) == ("aborted", "timed out")


def test_the_experiment_counts_success_by_the_truth():
    """An episode the navigator (and its outcome) calls succeeded but whose true pose ended 0.3 m
    off is a failure in the experiment's metrics, with both final errors in its row."""
    from amr_twin.experiments.navigation.metrics import measure

    cfg = load_config()
    t = np.arange(0.0, 10.0, 0.01)
    x = np.linspace(-9.0, -6.3, len(t))
    pose = np.column_stack([x, np.zeros_like(t), np.full_like(t, math.pi)])
    outcome = GoalOutcome(GOAL, status="succeeded", t_start_s=2.0, t_end_s=9.9)
    run = SimpleNamespace(
        outcomes=[outcome],
        t_s=t,
        pose_true=pose,
        commands=np.zeros((0, 3)),
        controller_cpu_s=np.zeros(0),
        collisions=[],
        monitor_actions={},
        sim_s=10.0,
        wall_s=1.0,
        actor_poses=[],
        final_errors=[final_errors(GOAL, pose[-1], (-6.1, 0.0, math.pi))],
    )
    episode = SimpleNamespace(
        index=0,
        seed=0,
        scenario="clear",
        start=(-9.0, 0.0, 0.0),
        goal=GOAL,
        obstacle=None,
        actor=None,
    )
    row = measure(cfg, "warehouse", episode, "true", run)
    assert row["success"] is False and row["barn_score"] == 0.0
    assert row["final_error_true_m"] == pytest.approx(0.3) and row[
        "final_error_estimate_m"
    ] == pytest.approx(0.1)
    run.final_errors = [final_errors(GOAL, (-6.2, 0.0, math.pi), (-6.1, 0.0, math.pi))]
    assert measure(cfg, "warehouse", episode, "true", run)["success"] is True
