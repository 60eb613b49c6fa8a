"""The navigator's plans and recoveries: a goal's end, a failure's recovery (round robin), when to
plan again and the new plan.

Reasons and measurements: docs/explanation/navigation.md#amr_twinnavigationnavigator."""

from __future__ import annotations

import math

import numpy as np

from amr_twin.navigation.path_handler import PathHandler


class Replanning:
    """The planning half of :class:`amr_twin.navigation.navigator.Navigator`, which holds the
    goals' outcomes, the planner, the costmap, the recoveries and the progress checker."""

    def _finish(self, status: str, reason: str = "") -> None:
        out = self.outcomes[self._goal_i]
        out.status, out.reason, out.t_end_s = status, reason, self.clock.now_s
        if self.pose_source.ready:
            out.pose_estimate_end = tuple(float(v) for v in self.pose_source.pose())
        self._goal_i += 1
        self._path = self._plan = self._recovery = None
        self._failures, self._blocked_since, self._rotating_to_goal = 0, None, False
        self._inside_since = self._yaw_inside_since = None
        self._next_plan_s = self.clock.now_s
        self.progress.reset()
        if status == "aborted":  # the goals after it are not attempted
            for later in self.outcomes[self._goal_i :]:
                later.status, later.reason = (
                    "aborted",
                    f"not attempted: an earlier goal failed ({reason})",
                )
            self._goal_i = len(self.outcomes)

    def _fail(self, why: str) -> None:
        """A failure of planning or control: the next recovery, or the goal aborted."""
        self._failures += 1
        out = self.outcomes[self._goal_i]
        if self._failures > self.p.max_failures:
            g = out.goal
            self._finish(
                "aborted",
                f"goal ({g[0]:.2f}, {g[1]:.2f}) not reached: {why} "
                f"(after {self.p.max_failures} recoveries)",
            )
            return
        name, make = self.recoveries[self._rr % len(self.recoveries)]
        self._rr += 1
        self._recovery = make(
            self.costmap,
            self.footprint,
            self.limits,
            self.dt_s,
            **self.recovery_settings.get(name, {}),
        )
        self._recovery.start(self.clock.now_s, self.pose_source.pose())
        out.recoveries.append((self.clock.now_s, name, why))
        self._blocked_since = None
        self.progress.reset()
        self.controller.reset()

    def _plan_stale(self, pose) -> bool:
        """Whether a new plan could differ: the costmap changed since the last one, or the robot
        left it by more than ``off_path_m`` (a plan is optimal from each of its points on the same
        costmap)."""
        if self.costmap.version != self._plan_version:
            return True
        self._next_plan_s = self.clock.now_s + 1.0 / self.p.planner_hz
        return self._path.distance_to_path_m(pose[0], pose[1]) > self.p.off_path_m

    def _replan(self, pose) -> bool:
        out = self.outcomes[self._goal_i]
        g = out.goal
        self._plan_version = self.costmap.version
        ppl = self.people
        standing = ppl.xy_m[
            (np.hypot(*ppl.v_m_s.T) == 0.0)
            & (np.hypot(*(ppl.xy_m - pose[:2]).T) > self.planner.people_m + 0.1)
        ]  # not those at the robot
        plan = self.planner.plan(pose[:2], np.array(g[:2]), None if len(g) < 3 else g[2], standing)
        if plan is None:  # nav2: clear the global costmap and try once more before failing
            self.costmap.clear()
            plan = self.planner.plan(
                pose[:2], np.array(g[:2]), None if len(g) < 3 else g[2], standing
            )
        self._next_plan_s = self.clock.now_s + 1.0 / self.p.planner_hz
        if plan is None:
            return False
        out.plan_cpu_s.append(plan.cpu_s)
        old = self._path
        if (
            old is not None
            and plan.length_m >= old.remaining_m
            and old.distance_to_path_m(pose[0], pose[1]) <= self.p.off_path_m
            and self.planner.path_free(old.poses[old.index :, :2], standing)
        ):
            # nav2's replanning only if the path becomes invalid: a longer plan leaves a free path
            # as it is (a tier's margin flickering with what the scans show of a pallet jack turned
            # the robot back and forth between two routes, the path's heading each time)
            return True
        if math.isnan(out.first_plan_length_m):
            out.first_plan_length_m = plan.length_m
        self._plan, self._path = plan, PathHandler(plan.poses)
        if self.outputs is not None:
            self.outputs.plan(plan)
        return True
