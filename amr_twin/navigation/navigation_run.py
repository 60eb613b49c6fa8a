"""A twin driven through a list of goals by the navigation stack: :func:`navigate` builds the twin,
attaches the stack (:func:`amr_twin.navigation.stack.attach`), runs until every goal has an outcome
and the robot stands, and returns a :class:`NavigationRun`.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np

from amr_twin.navigation.navigator import GoalOutcome
from amr_twin.navigation.stack import REST_S, NavigationOptions, attach, load_static_map
from amr_twin.navigation.static_map import StaticMap

LIMIT_BASE_S = 60.0
LIMIT_S_PER_M = 4.0
"""The default time limit of a run's goals, s: ``LIMIT_BASE_S`` + ``LIMIT_S_PER_M`` per metre of
their first plans, counted from the end of the rest (:func:`time_limit_s`)."""
SETTLE_MAX_S = 5.0
"""After the last goal ends, s: the navigator ramps the robot to a stop (0.8 s from 0.8 m/s at 1
m/s^2) within this."""
STANDING_RAD_S = 0.05
"""A wheel slower than this stands, rad/s (6 mm/s at the rim)."""


@dataclass
class NavigationRun:
    """What :func:`navigate` returns: each goal's outcome, the true trajectory, the commands, the
    costs."""

    outcomes: list[GoalOutcome]
    t_s: np.ndarray  # (n,) the recorder's 100 Hz grid
    pose_true: np.ndarray  # (n, 3) x_m, y_m, yaw_rad
    commands: np.ndarray  # (k, 3) t_s, v_m_s, w_rad_s published on cmd_vel
    controller_cpu_s: np.ndarray
    collisions: list = field(default_factory=list)
    monitor_actions: dict = field(default_factory=dict)
    sim_s: float = 0.0
    wall_s: float = 0.0
    timed_out: bool = False
    actor_poses: list = field(
        default_factory=list
    )  # (t_s, [(x_m, y_m, yaw_rad), ...]) of actors/poses, 10 Hz
    final_errors: list = field(
        default_factory=list
    )  # each goal's :class:`~.goal_truth.FinalErrors`


def time_limit_s(timeout_s: float | None, plan_lengths_m) -> float:
    """The run's time limit after the rest, s: ``timeout_s``, or (None) ``LIMIT_BASE_S`` plus
    ``LIMIT_S_PER_M`` per metre of the goals' first plans (NaN: no plan yet)."""
    if timeout_s is not None:
        return timeout_s
    return LIMIT_BASE_S + LIMIT_S_PER_M * sum(v for v in plan_lengths_m if not math.isnan(v))


def _goal_pose_in_map(msg, start) -> tuple[float, float, float]:
    """A ``geometry_msgs/PoseStamped`` goal in ``map`` (``odom``: placed by the start pose, where
    the wheel odometry's frame starts)."""
    p, yaw = msg.pose.position, msg.pose.orientation.yaw_rad()
    if msg.header.frame_id.lstrip("/") != "odom":
        return float(p.x), float(p.y), float(yaw)
    c, s = math.cos(start[2]), math.sin(start[2])
    return (
        float(start[0] + c * p.x - s * p.y),
        float(start[1] + s * p.x + c * p.y),
        float(math.remainder(start[2] + yaw, 2 * math.pi)),
    )


def navigate(
    cfg,
    twin_options,
    options: NavigationOptions,
    static: StaticMap | None = None,
    on_twin=None,
    progress=None,
    publish: bool = False,
    drive: bool = True,
) -> NavigationRun:
    """Build the twin (``twin_options``, sensors on), attach the stack, run until every goal has an
    outcome and the robot stands; each goal the navigator reached is then judged by the true pose
    (:mod:`.goal_truth`).

    ``on_twin(twin)`` is called once the twin is built (a recording's capture attaches there);
    ``progress(navigator, t_s)`` every simulated half second (it may :meth:`Navigator.cancel` the
    goals); ``publish``, ``drive``: as :func:`attach`. A ``geometry_msgs/PoseStamped`` on the bus'
    ``goal_pose`` (frame ``map``, or ``odom``) is a new goal that preempts the active one (nav2's
    ``/goal_pose``). Raises nothing for a failed goal: its outcome says it.
    """
    from dataclasses import replace

    from amr_twin.navigation.goal_truth import final_errors, judge
    from amr_twin.recording.recorder import attach_recorder
    from amr_twin.assembly.twin import Twin

    wall0 = time.perf_counter()
    static = (
        static if static is not None else load_static_map(cfg, twin_options.world, options.map_yaml)
    )
    twin = Twin(cfg, replace(twin_options, sensors=("imu", "lidar")))
    recorder = attach_recorder(twin)
    if on_twin is not None:
        on_twin(twin)
    nav = attach(twin, cfg, static, options, publish=publish, drive=drive)
    twin.navigator = nav
    twin.bus.subscribe(
        "goal_pose", lambda msg: nav.send_goal(_goal_pose_in_map(msg, twin.start_xy_yaw))
    )
    actor_poses = []
    twin.on_message(
        lambda _topic, msg, t_us: actor_poses.append(
            (
                t_us * 1e-6,
                [(p.position.x, p.position.y, p.orientation.yaw_rad()) for p in msg.poses],
            )
        ),
        ("actors/poses",),
    )
    twin.advance(REST_S)
    while not nav.done and not twin.halted:
        if twin.t_s >= REST_S + time_limit_s(
            options.timeout_s, [o.first_plan_length_m for o in nav.outcomes]
        ):
            break
        twin.advance(0.5)
        if progress is not None:
            progress(nav, twin.t_s)
    timed_out = not nav.done and not twin.halted
    if not nav.done:  # the robot stops; the goals end aborted
        why = (
            f"timed out at t = {twin.t_s:.1f} s"
            if timed_out
            else f"stopped by a collision at t = {twin.t_s:.1f} s"
        )
        ended = [o for o in nav.outcomes if o.status == "pending"]
        nav.cancel(why)
        for out in ended:
            out.status = "aborted"
    settle_end = twin.t_s + SETTLE_MAX_S
    while (
        not twin.halted
        and twin.t_s < settle_end
        and (
            (nav.commands and nav.commands[-1][1:] != (0.0, 0.0))
            or max(abs(w) for w in twin.observables.loop_sensors()[2:4]) > STANDING_RAD_S
        )
    ):
        twin.advance(0.1)  # the navigator ramps the robot to a stop, the drive follows
    if not twin.halted:
        twin.advance(0.5)  # the stop settles
    series = recorder.series()
    errors = []
    for i, out in enumerate(
        nav.outcomes
    ):  # each goal at its end; the last one where the robot came to stand
        last = i == len(nav.outcomes) - 1 or math.isnan(out.t_end_s)
        k = (
            len(series.t_s) - 1
            if last
            else min(int(np.searchsorted(series.t_s, out.t_end_s)), len(series.t_s) - 1)
        )
        estimate = (
            tuple(nav.pose_source.pose())
            if last and nav.pose_source.ready
            else out.pose_estimate_end
        )
        errors.append(final_errors(out.goal, series.pose[k], estimate))
        judge(out, errors[-1], nav.p.xy_tolerance_m, nav.p.yaw_tolerance_rad)
    cmds = np.array(nav.commands, float).reshape(-1, 3)
    return NavigationRun(
        nav.outcomes,
        series.t_s,
        series.pose,
        cmds,
        np.array(nav.controller_cpu_s),
        twin.collisions.as_dicts(),
        dict(nav.monitor.actions),
        twin.t_s,
        time.perf_counter() - wall0,
        timed_out,
        actor_poses,
        errors,
    )
