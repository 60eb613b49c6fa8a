"""The navigator node: goals in, ``cmd_vel`` out, on the twin's bus and clock (nav2's bt_navigator).

Reasons and measurements: docs/explanation/navigation.md#amr_twinnavigationnavigator."""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np

from amr_twin.estimation.ekf import POSE_TOPIC
from amr_twin.navigation.collision_monitor import CollisionMonitor
from amr_twin.navigation.interfaces import LocalController, Planner
from amr_twin.navigation.fleet_mates import FleetMates
from amr_twin.navigation.kinematics import Limits, rotation_rate, wrap
from amr_twin.navigation.map_matching import MapMatcher
from amr_twin.navigation.people import NOBODY, PeopleTracker
from amr_twin.navigation.perception import Perception
from amr_twin.navigation.progress import ProgressChecker
from amr_twin.navigation.registries import RECOVERIES, ROUND_ROBIN
from amr_twin.navigation.replanning import Replanning
from amr_twin.navigation.yielding import Yielding
from amr_twin.ros.geometry_messages import PoseWithCovarianceStamped, Twist


@dataclass(frozen=True)
class NavParams:
    """Rates, tolerances and ranges of the navigator (``navigation.navigator``, ``.costmap`` and
    ``.planner`` of the parameter file, where each has its source; the stack builds this from
    them)."""

    controller_hz: float = 20.0
    planner_hz: float = 1.0
    xy_tolerance_m: float = 0.25
    approach_m: float = 0.1
    approach_s: float = 2.0
    yaw_tolerance_rad: float = 0.25
    rotate_to_path_rad: float = math.radians(45.0)
    obstacle_range_m: float = 4.0
    raytrace_range_m: float = 5.0
    unmapped_m: float = 0.2
    blocked_s: float = 1.5
    off_path_m: float = 0.5
    max_failures: int = 6
    laser_xy_yaw: tuple = (0.3, 0.0, 0.0)


@dataclass
class GoalOutcome:
    """What became of one goal: ``succeeded``, ``aborted`` (with the reason), ``preempted`` (a new
    goal replaced it) or ``canceled``; times in s."""

    goal: tuple
    status: str = "pending"
    reason: str = ""
    t_start_s: float = math.nan
    t_end_s: float = math.nan
    recoveries: list = field(default_factory=list)  # (t_s, name)
    plan_cpu_s: list = field(default_factory=list)
    first_plan_length_m: float = math.nan
    pose_estimate_end: tuple | None = None  # the navigator's pose (x_m, y_m, yaw_rad) when it ended


class Navigator(Perception, Replanning):
    """Drive to each goal ``(x_m, y_m, yaw_rad or None)`` in turn (module docstring), from
    ``start_s``."""

    def __init__(
        self,
        bus,
        clock,
        pose_source,
        costmap,
        planner: Planner,
        controller: LocalController,
        footprint,
        limits: Limits,
        goals,
        params: NavParams = NavParams(),
        outputs=None,
        start_s: float = 0.0,
        *,
        monitor: CollisionMonitor | None = None,
        tracker: PeopleTracker | None = None,
        progress: ProgressChecker | None = None,
        recovery_settings: dict | None = None,
        matcher: MapMatcher | None = None,
        yielding: Yielding | None = None,
        recoveries: tuple = ROUND_ROBIN,
        fleet: FleetMates | None = None,
    ):
        self.bus, self.clock, self.pose_source = bus, clock, pose_source
        self.fleet = fleet
        """The fleet this robot belongs to (:class:`~amr_twin.navigation.fleet_mates.FleetMates`):
        its mates' returns are not tracked as people; None: a lone robot."""
        self._fleet_index = fleet.join(pose_source) if fleet is not None else -1
        self.yielding = yielding
        """Keeps the robot out of people's predicted paths
        (:class:`~amr_twin.navigation.yielding.Yielding`), or None."""
        self.matcher = matcher
        self.costmap, self.planner, self.controller = costmap, planner, controller
        self.footprint, self.limits, self.p = footprint, limits, params
        self.dt_s = 1.0 / params.controller_hz
        self.monitor = (
            monitor if monitor is not None else CollisionMonitor(footprint, limits.max_v_m_s)
        )
        self.progress = progress if progress is not None else ProgressChecker()
        self.recovery_settings = recovery_settings or {}
        """Each recovery's settings by its name (``spin``: ``angle_rad``, ...)."""
        self.recoveries = tuple((name, RECOVERIES.get(name)) for name in recoveries)
        """The recoveries' names and factories, in the round robin's order (:mod:`.registries`)."""
        self.outcomes = [GoalOutcome(tuple(g)) for g in goals]
        self.controller_cpu_s: list[float] = []
        self.commands: list[tuple] = []  # (t_s, v, w) published
        self.outputs = outputs
        self._goal_i, self._path, self._plan = 0, None, None
        self._next_plan_s, self._plan_version = 0.0, -1
        self._recovery, self._failures, self._rr = None, 0, 0
        self._blocked_since: float | None = None
        self._rotating_to_goal = False
        self._inside_since: float | None = (
            None  # when the estimate came within xy_tolerance_m of the goal
        )
        self._yaw_inside_since: float | None = (
            None  # when the heading came within yaw_tolerance_rad of the goal's
        )
        self._closest_m = math.inf
        self._scan_points = np.zeros((0, 2))
        self._unmapped = np.zeros(0, bool)
        self.tracker = tracker if tracker is not None else PeopleTracker()
        self.people = NOBODY
        """The tracked people (:class:`~amr_twin.navigation.people.People`) after the last scan."""
        self._cmd = bus.advertise("cmd_vel", Twist)
        self._matched = (
            bus.advertise(POSE_TOPIC, PoseWithCovarianceStamped)
            if matcher is not None and matcher.feedback
            else None
        )
        bus.subscribe("scan", self._on_scan)
        self._start_us = max(clock.now_us, int(round(start_s * 1e6)))
        self._timer = None
        if self.outcomes:
            self._start_timer()

    def _start_timer(self) -> None:
        first = max(self.clock.now_us, self._start_us)
        self._timer = self.clock.schedule_every(first, int(round(self.dt_s * 1e6)), self._on_timer)

    # -- goals from outside (a user, an action server) ---------------------------------------
    def send_goal(self, goal) -> GoalOutcome:
        """Drive to ``goal`` ``(x_m, y_m, yaw_rad or None)`` now: the active goal ends ``preempted``
        and the queued ones ``canceled``. Returns the new goal's outcome (filled in as it goes)."""
        self._end_all("preempted", "canceled", "replaced by a new goal")
        out = GoalOutcome(tuple(goal))
        self.outcomes.append(out)
        self._goal_i = len(self.outcomes) - 1
        if self._timer is None:
            self._start_timer()
        return out

    def cancel(self, reason: str = "canceled") -> None:
        """End the active goal and the queued ones as ``canceled``; the robot ramps to a stop."""
        self._end_all("canceled", "canceled", reason)

    def _end_all(self, active: str, queued: str, reason: str) -> None:
        if self.done:
            return
        self._finish(active, reason)
        for later in self.outcomes[self._goal_i :]:
            later.status, later.reason = queued, reason
        self._goal_i = len(self.outcomes)
        self.controller.reset()

    @property
    def active(self) -> GoalOutcome | None:
        """The goal being driven to, or None."""
        return None if self.done else self.outcomes[self._goal_i]

    @property
    def distance_left_m(self) -> float:
        """Length of the rest of the present plan, m (NaN before the first plan of the active
        goal)."""
        return math.nan if self.done or self._path is None else float(self._path.remaining_m)

    # -- state ----------------------------------------------------------------------------
    @property
    def done(self) -> bool:
        """Every goal has an outcome."""
        return self._goal_i >= len(self.outcomes)

    @property
    def plan(self):
        return self._plan

    # -- the control cycle ----------------------------------------------------------------------
    def _on_timer(self) -> None:
        if self.done or not self.pose_source.ready:
            vel = self._velocity()
            if self.done and vel == (0.0, 0.0):  # stopped: nothing more until a new goal
                self._timer.cancel()
                self._timer = None
                return
            v, w = self.limits.ramp(0.0, 0.0, *vel, self.dt_s) if self.done else (0.0, 0.0)
            self._publish(v, w)
            return
        now, pose, vel = self.clock.now_s, self.pose_source.pose(), self._velocity()
        out = self.outcomes[self._goal_i]
        if math.isnan(out.t_start_s):
            out.t_start_s = now
        v, w = self._cycle(now, pose, vel, out)
        if not self.done or (v, w) == (0.0, 0.0):
            self._publish(v, w)
        if self.outputs is not None:
            self.outputs.cycle(now, pose, self.costmap)

    def _velocity(self) -> tuple[float, float]:
        """The last command (what the drive is ramping to): a cleaner velocity than the
        estimate's."""
        return (self.commands[-1][1], self.commands[-1][2]) if self.commands else (0.0, 0.0)

    def _arrived(self, now: float, pose, goal) -> bool:
        """Time to stop and turn to the goal's yaw: within ``approach_m`` of the goal, or within
        ``xy_tolerance_m`` and no longer closing in (``approach_s`` inside it, or 2 cm past the
        closest approach)."""
        d = math.hypot(pose[0] - goal[0], pose[1] - goal[1])
        if d <= min(self.p.approach_m, self.p.xy_tolerance_m):
            return True
        if d > self.p.xy_tolerance_m:
            self._inside_since = None
            return False
        if self._inside_since is None:
            self._inside_since, self._closest_m = now, d
        self._closest_m = min(self._closest_m, d)
        return now - self._inside_since >= self.p.approach_s or d > self._closest_m + 0.02

    def _cycle(self, now: float, pose, vel, out: GoalOutcome) -> tuple[float, float]:
        lim, g = self.limits, out.goal
        if self._recovery is not None:
            step = self._recovery.step(now, pose, vel)
            if not step.done:
                return step.v_m_s, step.w_rad_s
            self._recovery = None
            self._next_plan_s = now  # replan at once
            return lim.ramp(0.0, 0.0, *vel, self.dt_s)
        if self._rotating_to_goal or self._arrived(now, pose, g):
            self._rotating_to_goal = True
            err = 0.0 if len(g) < 3 or g[2] is None else float(wrap(g[2] - pose[2]))
            if abs(err) <= self.p.yaw_tolerance_rad and abs(vel[0]) < 0.05 and abs(vel[1]) < 0.1:
                self._finish("succeeded")
                return 0.0, 0.0
            inside = abs(err) <= self.p.yaw_tolerance_rad
            if not inside:
                self._yaw_inside_since = None
            elif self._yaw_inside_since is None:
                self._yaw_inside_since = now
            # inside the tolerance: on to half of it for at most approach_s (a drive that cannot
            # turn slowly, as the thesis' firmware with its dead zone, would otherwise never end the
            # goal)
            settled = inside and (
                abs(err) <= 0.5 * self.p.yaw_tolerance_rad
                or now - self._yaw_inside_since >= self.p.approach_s
            )
            w = 0.0 if settled else rotation_rate(err, lim, vel[1], self.dt_s)
            return lim.ramp(0.0, w, *vel, self.dt_s)
        if self._path is None or (now >= self._next_plan_s and self._plan_stale(pose)):
            if not self._replan(pose):
                self._fail(self.planner.last_error or "no plan")
                return lim.ramp(0.0, 0.0, *vel, self.dt_s)
        path = self._path
        path.update(pose[0], pose[1])
        if not self.progress.check(now, pose[0], pose[1]):
            self._fail("failed to make progress")
            return lim.ramp(0.0, 0.0, *vel, self.dt_s)
        ahead = path.ahead(0.6)[-1]
        heading = math.atan2(ahead[1] - pose[1], ahead[0] - pose[0])
        err = float(wrap(heading - pose[2]))
        if path.remaining_m > 0.3 and (
            abs(err) > self.p.rotate_to_path_rad
            or (abs(err) > 0.15 and abs(vel[0]) < 0.02 and vel[1] != 0.0)
        ):
            self.controller.reset()
            return lim.ramp(0.0, rotation_rate(err, lim, vel[1], self.dt_s), *vel, self.dt_s)
        t0 = time.process_time()
        people = (
            self.people if self.controller.sees_people else NOBODY
        )  # else the monitor's people zones alone
        cmd = self.controller.command(pose, vel, path, people, now)
        self.controller_cpu_s.append(time.process_time() - t0)
        if cmd.blocked:
            self._blocked_since = now if self._blocked_since is None else self._blocked_since
            if now - self._blocked_since >= self.p.blocked_s:
                self._fail("the way ahead is blocked")
        else:
            self._blocked_since = None
        return cmd.v_m_s, cmd.w_rad_s
