"""The navigator on the ROS 1 graph as move_base: :class:`NavigationServer`.

Reasons and measurements: docs/how-to/ros1.md#amr_twinros1navigation_server."""

from __future__ import annotations

import logging
import math

from amr_twin.live.pacer import PacerClosed
from amr_twin.analysis.se2 import yaw_of_quaternion

LOG = logging.getLogger(__name__)

GLOBAL_FRAME = "map"
ACTION = "move_base"
SIMPLE_GOAL = "move_base_simple/goal"
FEEDBACK_PERIOD_US = 100_000
"""Period of the action's feedback, simulated us (move_base's: its controller's 20 Hz; 10 Hz is
enough for a client that watches)."""
PYTHON_MODULES = ("actionlib", "actionlib_msgs", "move_base_msgs")
DEBIAN_PACKAGES = ("python3-actionlib", "python3-move-base-msgs")


def missing() -> str | None:
    """One line naming the Debian packages the action server lacks; None when it has them."""
    from pathlib import Path

    from amr_twin.ros1.installation import DIST_PACKAGES

    absent = [m for m in PYTHON_MODULES if not (Path(DIST_PACKAGES) / m).is_dir()]
    if not absent:
        return None
    return (
        f"the move_base action server needs {', '.join(absent)}: install Debian's "
        f"{' '.join(DEBIAN_PACKAGES)}"
    )


def pose_problem(pose_stamped) -> tuple[str, tuple | None]:
    """Why a ``geometry_msgs/PoseStamped`` (rospy's) is not a goal in one line ('' if it is) and the
    goal ``(x_m, y_m, yaw_rad)``; move_base's checks: its frame, finite numbers, a rotation about z
    alone."""
    frame = pose_stamped.header.frame_id.lstrip("/")
    if frame != GLOBAL_FRAME:
        return (
            f"target_pose.header.frame_id {pose_stamped.header.frame_id!r}: goals are taken in "
            f"{GLOBAL_FRAME!r} only (the global frame)"
        ), None
    p, q = pose_stamped.pose.position, pose_stamped.pose.orientation
    if not all(math.isfinite(v) for v in (p.x, p.y, p.z, q.x, q.y, q.z, q.w)):
        return "target_pose.pose: every value must be finite", None
    norm = math.sqrt(q.x * q.x + q.y * q.y + q.z * q.z + q.w * q.w)
    if norm < 1e-6:
        return "target_pose.pose.orientation: a quaternion of length 0 is no rotation", None
    x, y, z, w = q.x / norm, q.y / norm, q.z / norm, q.w / norm
    if 1.0 - 2.0 * (x * x + y * y) < 1.0 - 1e-3:  # the rotated z axis' vertical component
        return (
            "target_pose.pose.orientation: must be a rotation about z (the goal is on the floor)",
            None,
        )
    return "", (
        float(p.x),
        float(p.y),
        yaw_of_quaternion(w, x, y, z),
    )


class NavigationServer:
    """move_base's action, its simple goal and maps for ``navigator`` on ``twin``; a sink of
    ``pacer``.

    ``checker``: a :class:`~amr_twin.navigation.planner.GlobalPlanner` on the static map alone, for
    the goals' checks. Built after the ROS 1 session has joined the graph; :meth:`close` at the end
    of the run."""

    def __init__(self, twin, pacer, navigator, checker, say=print):
        from amr_twin.ros1.installation import import_rospy
        from amr_twin.ros1.navigation_maps import NavigationMaps

        self.rospy = rospy = import_rospy()
        import actionlib
        from geometry_msgs.msg import PoseStamped
        from move_base_msgs.msg import (
            MoveBaseAction,
            MoveBaseActionGoal,
            MoveBaseFeedback,
            MoveBaseResult,
        )

        self.twin, self.pacer, self.nav, self.checker = twin, pacer, navigator, checker
        self._feedback_cls, self._result_cls, self._action_goal_cls = (
            MoveBaseFeedback,
            MoveBaseResult,
            MoveBaseActionGoal,
        )
        self._pose_cls = PoseStamped
        self._ids = actionlib.GoalIDGenerator()
        self._goals: list = []
        """(goal handle, GoalOutcome) of the goals sent to the navigator and not reported yet
        (twin's thread)."""
        self._next_feedback_us = 0
        self._closed = False
        self.set_time(twin.clock.now_us)
        self.maps = NavigationMaps(twin, navigator)
        self.server = actionlib.ActionServer(
            ACTION, MoveBaseAction, self._on_goal, self._on_cancel, auto_start=False
        )
        self.server.start()
        self._simple = rospy.Subscriber(
            SIMPLE_GOAL, PoseStamped, self._on_simple_goal, queue_size=10
        )
        pacer.sinks.append(self)
        say(
            f"ros1: move_base on {rospy.resolve_name(ACTION)} (goals in frame {GLOBAL_FRAME!r}; "
            f"{rospy.resolve_name(SIMPLE_GOAL)}), maps on {rospy.resolve_name('map')}"
        )

    def set_time(self, t_us: int) -> None:
        """rospy's time in the twin's process: simulated ``t_us`` (the twin does not read its own
        ``/clock``)."""
        import rospy.rostime

        rospy.rostime._set_rostime(self.rospy.Time(t_us // 1_000_000, t_us % 1_000_000 * 1000))

    # -- rospy's threads: post to the twin's
    # ------------------------------------------------------------
    def _on_goal(self, handle) -> None:
        handle.set_accepted()
        problem, goal = pose_problem(handle.get_goal().target_pose)
        self._post(lambda: self._start(handle, goal, problem), handle)

    def _on_cancel(self, handle) -> None:
        self._post(lambda: self._cancel(handle), handle)

    def _on_simple_goal(self, msg) -> None:
        """As move_base: the pose becomes a goal of the action (its status and result on the
        graph)."""
        if self._closed:
            return
        action_goal = self._action_goal_cls()
        action_goal.header.stamp = self.rospy.Time.now()
        action_goal.goal_id = self._ids.generate_ID()
        action_goal.goal.target_pose = msg
        self.server.internal_goal_callback(action_goal)

    def _post(self, call, handle) -> None:
        try:
            self.pacer.post(call)
        except PacerClosed:
            handle.set_aborted(None, "the twin's run is over")

    # -- the twin's thread
    # ---------------------------------------------------------------------------------
    def _start(self, handle, goal, problem: str) -> None:
        if not problem:
            here = (
                self.nav.pose_source.pose()
                if self.nav.pose_source.ready
                else self.twin.start_xy_yaw
            )
            if self.checker.plan(here[:2], goal[:2]) is None:
                problem = self.checker.last_error
        if problem:
            if self.nav.active is not None:
                self.nav.cancel("replaced by a goal that was refused")
            handle.set_aborted(None, problem)
            LOG.warning("ros1: move_base goal refused: %s", problem)
            return
        self._goals.append((handle, self.nav.send_goal(goal)))
        self._next_feedback_us = self.twin.clock.now_us

    def _cancel(self, handle) -> None:
        goal_id = handle.get_goal_id().id
        for gh, outcome in self._goals:
            if gh.get_goal_id().id == goal_id and outcome is self.nav.active:
                self.nav.cancel("canceled by the action's client")

    def flush(self, t_us: int) -> None:
        """At each pacer tick: rospy's time, each goal's new state, the feedback, the maps."""
        self.set_time(t_us)
        for item in list(self._goals):
            handle, outcome = item
            if outcome.status == "pending":
                continue
            self._goals.remove(item)
            if outcome.status == "succeeded":
                handle.set_succeeded(self._result_cls(), f"reached at t = {outcome.t_end_s:.2f} s")
            elif outcome.status == "aborted":
                handle.set_aborted(self._result_cls(), outcome.reason)
            else:  # preempted by a new goal, or canceled
                handle.set_canceled(self._result_cls(), outcome.reason or outcome.status)
        active = self.nav.active
        if t_us >= self._next_feedback_us and any(o is active for _h, o in self._goals):
            self._next_feedback_us = t_us + FEEDBACK_PERIOD_US
            self._feedback(t_us, next(h for h, o in self._goals if o is active))
        self.maps.flush(t_us)

    def _feedback(self, t_us: int, handle) -> None:
        source = self.nav.pose_source
        if not source.ready:
            return
        x, y, yaw = (float(v) for v in source.pose())
        fb = self._feedback_cls()
        pose = fb.base_position
        pose.header.stamp = self.rospy.Time(t_us // 1_000_000, t_us % 1_000_000 * 1000)
        pose.header.frame_id = GLOBAL_FRAME
        pose.pose.position.x, pose.pose.position.y = x, y
        pose.pose.orientation.z, pose.pose.orientation.w = math.sin(yaw / 2), math.cos(yaw / 2)
        handle.publish_feedback(fb)

    def close(self) -> None:
        """The run is over: goals still going end ABORTED (saying so); the subscriptions end."""
        if self._closed:
            return
        self._closed = True
        t_s = self.twin.clock.now_s
        for handle, outcome in self._goals:
            handle.set_aborted(
                self._result_cls(),
                f"the twin's run ended at t = {t_s:.2f} s before the goal had an outcome",
            )
        self._goals.clear()
        self._simple.unregister()
        self.maps.close()
