"""A goal judged by the truth: where the robot really ended against where the navigator thought it
was.

The navigator declares a goal reached from its own pose (the localisation's estimate); the twin
knows the true pose. :func:`final_errors` gives both distances to the goal; :func:`judge` keeps a
goal ``succeeded`` only if the true pose is within the goal checker's tolerances (xy and, for a
goal with a yaw, yaw), otherwise it becomes ``aborted`` with the reason ("reached by the
estimate, true pose 0.29 m from the goal").
"""

from __future__ import annotations

import math
from dataclasses import dataclass


@dataclass(frozen=True)
class FinalErrors:
    """Distance (m) and heading error (rad, None for a goal without a yaw) from the goal, by the
    truth and by the navigator's estimate (None where the navigator had no pose)."""

    true_xy_m: float
    true_yaw_rad: float | None
    estimate_xy_m: float | None
    estimate_yaw_rad: float | None

    def within(self, xy_tolerance_m: float, yaw_tolerance_rad: float) -> bool:
        """Whether the TRUE pose is within the tolerances."""
        return self.true_xy_m <= xy_tolerance_m and (
            self.true_yaw_rad is None or self.true_yaw_rad <= yaw_tolerance_rad
        )

    def as_json(self) -> dict:
        """The errors with yaw in degrees (JSON keys name their units)."""
        deg = lambda v: None if v is None else math.degrees(v)  # noqa: E731
        return {
            "true_xy_m": self.true_xy_m,
            "true_yaw_deg": deg(self.true_yaw_rad),
            "estimate_xy_m": self.estimate_xy_m,
            "estimate_yaw_deg": deg(self.estimate_yaw_rad),
        }


def _errors(goal, pose) -> tuple[float | None, float | None]:
    if pose is None:
        return None, None
    xy = math.hypot(pose[0] - goal[0], pose[1] - goal[1])
    has_yaw = len(goal) > 2 and goal[2] is not None
    return xy, abs(math.remainder(pose[2] - goal[2], 2 * math.pi)) if has_yaw else None


def final_errors(goal, pose_true, pose_estimate=None) -> FinalErrors:
    """The errors of poses ``(x_m, y_m, yaw_rad)`` from ``goal`` ``(x_m, y_m, yaw_rad or None)``."""
    true_xy, true_yaw = _errors(goal, pose_true)
    est_xy, est_yaw = _errors(goal, pose_estimate)
    return FinalErrors(true_xy, true_yaw, est_xy, est_yaw)


def judge(outcome, errors: FinalErrors, xy_tolerance_m: float, yaw_tolerance_rad: float) -> None:
    """A ``succeeded`` ``outcome`` (:class:`~amr_twin.navigation.navigator.GoalOutcome`) whose true
    pose misses the tolerances becomes ``aborted``, its reason saying by how much; other outcomes
    are left as they are."""
    if outcome.status != "succeeded" or errors.within(xy_tolerance_m, yaw_tolerance_rad):
        return
    if errors.true_xy_m > xy_tolerance_m:
        miss = (
            f"true pose {errors.true_xy_m:.3f} m from the goal (tolerance {xy_tolerance_m:.3f} m)"
        )
    else:
        miss = (
            f"true heading {math.degrees(errors.true_yaw_rad):.0f} deg off the goal's (tolerance "
            f"{math.degrees(yaw_tolerance_rad):.0f} deg)"
        )
    outcome.status, outcome.reason = "aborted", f"reached by the estimate, {miss}"
