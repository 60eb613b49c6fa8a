"""The navigation stack on a twin: its map, its localisation, the navigator, driven to the end.

:func:`true_map` and :func:`load_static_map` give the static layer's map (the world's true map, or
a map_server YAML: a map the fusion experiment saved, an imported ROS map). :func:`attach` puts
on a running twin's bus what a ROS graph of the robot would run: the cmd_vel diff-drive node, the
localisation the user picks (ground truth, the EKF of odometry + gyro + UWB with its UWB tag, the
wheel odometry alone, or a plug-in's) and the :class:`~amr_twin.navigation.navigator.Navigator` with
the controller, planner and recoveries named in :class:`NavigationOptions`
(:mod:`amr_twin.navigation.registries`), which starts after ``REST_S`` standing still (the EKF's
gyro calibration).
:func:`amr_twin.navigation.navigation_run.navigate` runs a twin through a list of goals.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path


from amr_twin.navigation.collision_monitor import CollisionMonitor
from amr_twin.navigation.costmap import Costmap
from amr_twin.navigation.fleet_mates import FleetMates
from amr_twin.navigation.footprint import Footprint, robot_footprint
from amr_twin.navigation.kinematics import Limits
from amr_twin.navigation.interfaces import LocalisationSource, Planner
from amr_twin.navigation.localisation import PoseSource
from amr_twin.navigation.map_matching import MapMatcher
from amr_twin.navigation.navigator import Navigator, NavParams
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


def robot_top_m(cfg) -> float:
    """Height of the robot's highest part (the LiDAR's top), m: what stands lower than this can be
    hit."""
    lidar = cfg.components.lidar
    return float(lidar.pos_m[2] + lidar.size_m[2] / 2)


def true_map(cfg, world: str) -> StaticMap:
    """The world's true map: every world geom from the floor to the robot's top
    (:func:`world_map`)."""
    import mujoco

    from amr_twin.model.world_spec import world_compile_error, world_file

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
    fleet: FleetMates | None = None,
) -> Navigator:
    """Put the diff-drive node (unless ``drive`` is False: a live session brings its own), the
    localisation and the navigator on ``twin``'s bus (module docstring); ``publish``: the plan, map,
    costmap and footprint messages (:mod:`amr_twin.navigation.outputs`) too; ``fleet``: the fleet
    whose members share their poses (:func:`fleet_mates`), None for a robot on its own."""
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
    people.pop("fleet_margin_m")
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
        fleet=fleet,
    )


def fleet_mates(cfg) -> FleetMates:
    """A fleet whose robots share their pose estimates (pass it to :func:`attach` of each): a
    return within a mate's circumscribed radius plus ``navigation.people.fleet_margin_m`` of its
    estimate is not tracked as a person."""
    margin = cfg.navigation.people.fleet_margin_m
    return FleetMates(robot_footprint(cfg).circumscribed_radius_m + margin)


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
