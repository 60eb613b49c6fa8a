"""The navigation stack on a twin: its map, its localisation, the navigator, driven to the end.

:func:`true_map` and :func:`load_static_map` give the static layer's map (the world's true map, or
a map_server YAML: a map the fusion experiment saved, an imported ROS map). :func:`attach` puts
on a running twin's bus what a ROS graph of the robot would run: the cmd_vel diff-drive node, the
localisation the user picks (ground truth, the EKF of odometry + gyro + UWB with its UWB tag, the
wheel odometry alone, or a plug-in's) and the :class:`~amr_twin.navigation.navigator.Navigator` with
the controller, planner and recoveries named in :class:`NavigationOptions`
(:mod:`amr_twin.navigation.registries`), which starts after ``REST_S`` standing still (the EKF's
gyro calibration).
:func:`navigate` runs a twin through a list of goals and returns a :class:`NavigationRun`.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from amr_twin.navigation.collision_monitor import CollisionMonitor
from amr_twin.navigation.costmap import Costmap
from amr_twin.navigation.footprint import Footprint, robot_footprint
from amr_twin.navigation.kinematics import Limits
from amr_twin.navigation.interfaces import LocalisationSource, Planner
from amr_twin.navigation.localisation import PoseSource
from amr_twin.navigation.map_matching import MapMatcher
from amr_twin.navigation.navigator import GoalOutcome, Navigator, NavParams
from amr_twin.navigation.outputs import NavOutputs
from amr_twin.navigation.people import PeopleTracker
from amr_twin.navigation.progress import ProgressChecker
from amr_twin.navigation.registries import CONTROLLERS, LOCALISATIONS, PLANNERS, ROUND_ROBIN
from amr_twin.navigation.static_map import StaticMap, world_map, yaml_map
from amr_twin.navigation.yielding import Yielding

REST_S = 2.0
"""Standing still before the first goal: the gyro's rest calibration of the EKF
(ekf.imu_rest_calibration_s)."""
RESOLUTION_M = 0.05
LIMIT_BASE_S = 60.0
LIMIT_S_PER_M = 4.0
"""The default time limit of a run's goals, s: ``LIMIT_BASE_S`` + ``LIMIT_S_PER_M`` per metre of
their first plans, counted from the end of the rest (:func:`time_limit_s`)."""
SETTLE_MAX_S = 5.0
"""After the last goal ends, s: the navigator ramps the robot to a stop (0.8 s from 0.8 m/s at 1
m/s^2) within this."""
STANDING_RAD_S = 0.05
"""A wheel slower than this stands, rad/s (6 mm/s at the rim)."""


@dataclass(frozen=True)
class NavigationOptions:
    """Goals ``(x_m, y_m, yaw_rad or None)``, the map (None: the world's true map), and the plug-ins
    by their names in :mod:`amr_twin.navigation.registries`: localisation, controller, planner,
    recoveries."""

    goals: tuple
    map_yaml: str | None = None
    localisation: str = "ekf"
    controller: str = "mppi"
    seed: int = 0
    timeout_s: float | None = None  # None: time_limit_s's default
    planner: str = "grid"
    recoveries: tuple = ROUND_ROBIN  # tried in turn, one per failure


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


def robot_top_m(cfg) -> float:
    """Height of the robot's highest part (the LiDAR's top), m: what stands lower than this can be
    hit."""
    lidar = cfg.components.lidar
    return float(lidar.pos_m[2] + lidar.size_m[2] / 2)


def true_map(cfg, world: str) -> StaticMap:
    """The world's true map: every world geom from the floor to the robot's top
    (:func:`world_map`)."""
    import mujoco

    from amr_twin.model.build import world_compile_error, world_file

    path = world_file(world)
    if path.suffix.lower() in (".yaml", ".yml"):
        return yaml_map(path)
    try:
        model = mujoco.MjModel.from_xml_path(str(path))
    except ValueError as exc:
        raise world_compile_error(world, exc) from None
    return world_map(model, RESOLUTION_M, 0.005, robot_top_m(cfg), source=f"world {world}")


def load_static_map(cfg, world: str, map_yaml: str | None) -> StaticMap:
    """The static layer's map: ``map_yaml`` (map_server) when given, else the world's true map."""
    return yaml_map(Path(map_yaml)) if map_yaml else true_map(cfg, world)


def make_costmap(static: StaticMap, footprint: Footprint, nav) -> Costmap:
    """The costmap of a map for the robot's footprint and the settings ``nav`` (``cfg.navigation``);
    unknown cells are free to plan through (nav2's ``allow_unknown``, its default): a map built from
    scans leaves cells unknown along the rack faces."""
    c = nav.costmap
    return Costmap(
        static,
        footprint.inscribed_radius_m,
        c.inflation_radius_m,
        c.cost_scaling_per_m,
        unknown_is_lethal=False,
        static_tolerance_m=c.static_tolerance_m,
    )


def make_planner(costmap: Costmap, footprint: Footprint, nav, name: str = "grid") -> Planner:
    """The global planner ``name`` (:data:`~amr_twin.navigation.registries.PLANNERS`) on ``costmap``
    with ``nav``'s settings (``cfg.navigation``)."""
    return PLANNERS.get(name)(costmap, footprint, nav)


def attach(
    twin,
    cfg,
    static: StaticMap,
    options: NavigationOptions,
    publish: bool = True,
    drive: bool = True,
) -> Navigator:
    """Put the diff-drive node (unless ``drive`` is False: a live session brings its own), the
    localisation and the navigator on ``twin``'s bus (module docstring); ``publish``: the plan, map,
    costmap and footprint messages (:mod:`amr_twin.navigation.outputs`) too."""
    from amr_twin.controllers.diff_drive import DiffDriveNode

    source = LOCALISATIONS.get(options.localisation)()
    make_controller = CONTROLLERS.get(options.controller)
    if drive:
        DiffDriveNode(twin.bus, twin.clock, twin.client)
    source.attach(twin, cfg)  # the estimator that publishes its topic
    pose_source = PoseSource(
        twin.bus, source.topic, (0.0, 0.0, 0.0) if source.in_map else twin.start_xy_yaw
    )
    nav, footprint = cfg.navigation, robot_footprint(cfg)
    costmap = make_costmap(static, footprint, nav)
    limits = Limits(**nav.limits.model_dump())
    n, c, pl = nav.navigator, nav.costmap, nav.planner
    params = NavParams(
        controller_hz=n.controller_hz,
        planner_hz=pl.planner_hz,
        xy_tolerance_m=n.xy_tolerance_m,
        approach_m=n.approach_m,
        approach_s=n.approach_s,
        yaw_tolerance_rad=n.yaw_tolerance_rad,
        rotate_to_path_rad=n.rotate_to_path_rad,
        obstacle_range_m=c.obstacle_range_m,
        raytrace_range_m=c.raytrace_range_m,
        unmapped_m=c.unmapped_m if options.map_yaml is None else c.unmapped_map_file_m,
        blocked_s=n.blocked_s,
        off_path_m=pl.off_path_m,
        max_failures=n.max_failures,
        laser_xy_yaw=(
            float(cfg.components.lidar.pos_m[0]),
            float(cfg.components.lidar.pos_m[1]),
            0.0,
        ),
    )
    controller = make_controller(costmap, footprint, nav, options.seed)
    people = nav.people.model_dump()
    radius = people.pop("person_radius_m")
    yielding = make_yielding(footprint, limits, nav, 1.0 / n.controller_hz, people.pop("yielding"))
    monitor = CollisionMonitor(
        footprint,
        limits.max_v_m_s,
        person_radius_m=radius,
        decel_m_s2=limits.decel_m_s2,
        **nav.monitor.model_dump(),
    )
    r = nav.recoveries
    recovery_settings = {
        "spin": {"angle_rad": r.spin_rad},
        "wait": {"duration_s": r.wait_s},
        "backup": {"distance_m": r.backup_m, "speed_m_s": r.backup_m_s},
    }
    outputs = NavOutputs(twin.bus, twin.clock, costmap, footprint) if publish else None
    planner = make_planner(costmap, footprint, nav, options.planner)
    return Navigator(
        twin.bus,
        twin.clock,
        pose_source,
        costmap,
        planner,
        controller,
        footprint,
        limits,
        options.goals,
        params,
        outputs=outputs,
        start_s=twin.t_s + REST_S,
        monitor=monitor,
        tracker=PeopleTracker(**people),
        progress=ProgressChecker(n.progress_radius_m, n.progress_time_s),
        recovery_settings=recovery_settings,
        matcher=make_matcher(costmap, nav, source),
        yielding=yielding,
        recoveries=options.recoveries,
    )


def make_yielding(
    footprint: Footprint, limits: Limits, nav, dt_s: float, y: dict
) -> Yielding | None:
    """The robot's giving way to people (``navigation.people.yielding`` as ``y``), None when
    disabled."""
    if not y.pop("enabled"):
        return None
    m, p = nav.monitor, nav.people
    return Yielding(
        footprint,
        limits,
        dt_s,
        person_radius_m=p.person_radius_m,
        stop_m=m.people_stop_m,
        stop_lag_s=m.people_stop_lag_s,
        horizon_s=p.horizon_s,
        min_speed_m_s=p.min_speed_m_s,
        **y,
    )


def make_matcher(costmap: Costmap, nav, source: LocalisationSource) -> MapMatcher | None:
    """The scan-to-map correction of ``source``'s pose (``navigation.map_matching``); none for the
    true pose or when disabled; fed back only to a source that takes it in (the EKF)."""
    m = nav.map_matching.model_dump()
    if source.exact or not m.pop("enabled"):
        return None
    m["feedback"] = m["feedback"] and source.takes_matches
    return MapMatcher(costmap, **m)


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
