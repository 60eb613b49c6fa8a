"""Thesis chapter 6 in the twin: one warehouse drive, five localisation estimates.

§6.2.2 compares four architectures it could only cite (figs. 6.4 to 6.8). Here the
twin drives a route once and every architecture is fed the same recorded streams:

* ``odom``: raw wheel odometry (the firmware's published wheel speeds, dead-reckoned);
* ``odom+lidar``: LiDAR odometry (kiss-icp) with wheel odometry as the motion prior,
  the scan-matching front end of fig. 6.4's SLAM, and the map built from its poses;
* ``odom+imu``: EKF fusing the wheel twist with the gyro's yaw rate (fig. 6.5);
* ``odom+uwb``: EKF fusing the wheel twist with UWB ranges (fig. 6.6);
* ``odom+uwb+imu``: EKF fusing all three (fig. 6.7).

The route is followed by a pure-pursuit node on ``cmd_vel`` fed with the **true**
pose (a perfect localiser, as Gazebo's ``p3d`` plugin gives), so that the drive does
not depend on any estimator and all five see one trajectory. The estimators then
run offline on the recorded messages, replayed in stamp order: the numbers are
those an online run would give, and one drive serves all five.

:func:`run` drives and estimates (:mod:`.estimators`; its typed result in :mod:`.results`);
:func:`.plot.plot` and :func:`.report.report` write the twin's own fig. 6.8, the map and the tables.
"""

from __future__ import annotations

import math
import time
from pathlib import Path

import numpy as np

from amr_twin.model.config import TwinConfig
from amr_twin.controllers.diff_drive import DiffDriveNode
from amr_twin.controllers.path_follower import PathFollowerNode
from amr_twin.controllers.route import Route, distance_to_path_m, load_route, route_length_m
from amr_twin.recording.recorder import attach_recorder, recorder_of
from amr_twin.assembly.twin import Twin, TwinOptions
from amr_twin.analysis.trajectory import errors
from amr_twin.model.world_geometry import Footprints, scan_plane_boxes
from amr_twin.experiments.fusion.map import build_map
from amr_twin.experiments.fusion.estimators import (
    estimate_ekf,
    estimate_lidar,
    estimate_odom,
    last_per_stamp,
)
from amr_twin.experiments.fusion.results import FusionResults
from amr_twin.experiments.fusion.robot import NOMINAL, RobotErrors, draw
from amr_twin.experiments.fusion.streams import Streams

ROUTES_DIR = Path(__file__).resolve().parents[1] / "routes"
DEFAULT_ROUTE = ROUTES_DIR / "warehouse_60m.yaml"
ARCHITECTURES = ("odom", "odom+lidar", "odom+imu", "odom+uwb", "odom+uwb+imu")
REST_S = 2.0  # standing still before the route: the IMU's rest calibration
TAIL_S = 1.0  # standing still after the goal
TIMEOUT_FACTOR = 3.0  # give up after this many times the route's length / max speed
RPE_DELTA_M = 1.0


def drive(
    cfg: TwinConfig,
    route: Route,
    *,
    seed: int = 0,
    firmware: str = "improved",
    progress: bool = True,
    rrd_path: Path | None = None,
    mcap_path: Path | None = None,
    robot: RobotErrors = NOMINAL,
) -> tuple[Twin, Streams, bool]:
    """Drive ``route`` in its world with IMU, LiDAR and UWB on; return the twin and the recorded
    streams.

    ``robot``: the robot's own errors (its true wheel geometry and hall sensors; the odometry
    keeps the nominal geometry of ``cfg``). ``rrd_path`` / ``mcap_path``: also write the
    drive as a Rerun / MCAP recording.
    """
    recording = rrd_path is not None or mcap_path is not None
    twin = Twin(
        robot.config(cfg),
        TwinOptions(
            firmware=firmware,
            world=route.world,
            seed=seed,
            start_xy_yaw=route.start_xy_yaw,
            sensors=("imu", "lidar"),
            visuals=recording,
            **robot.twin_options(),
        ),
    )
    twin.add_sensor("uwb")
    attach_recorder(twin)
    streams = Streams()
    twin.on_message(streams.tap)
    if recording:
        from amr_twin.recording.rerun_capture import attach

        attach(twin)
    DiffDriveNode(twin.bus, twin.clock, twin.client)
    twin.advance(REST_S)

    def true_pose() -> tuple[float, float, float]:
        p = twin.physics.pose()
        return p.x_m, p.y_m, p.yaw_rad

    follower = PathFollowerNode(twin.bus, twin.clock, route, pose_source=true_pose)
    length_m = route_length_m(route)
    timeout_s = REST_S + TIMEOUT_FACTOR * length_m / route.max_speed_m_s
    bar = _progress_bar(progress, length_m)
    travelled_m, last = 0.0, true_pose()
    while not follower.done and twin.t_s < timeout_s:
        twin.advance(0.5)
        now = true_pose()
        travelled_m += math.hypot(now[0] - last[0], now[1] - last[1])
        last = now
        if bar is not None:
            bar[0].update(bar[1], completed=min(travelled_m, length_m))
    twin.advance(TAIL_S)
    if bar is not None:
        bar[0].stop()
    if rrd_path is not None or mcap_path is not None:
        from amr_twin.recording.rerun_log import record_run

        record_run(twin, rrd_path=rrd_path, mcap_path=mcap_path)
    return twin, streams, bool(follower.done)


def _progress_bar(enabled: bool, total_m: float):
    if not enabled:
        return None
    from rich.console import Console
    from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn

    bar = Progress(
        TextColumn("fusion drive"),
        BarColumn(),
        TextColumn("{task.completed:.0f}/{task.total:.0f} m"),
        TimeElapsedColumn(),
        console=Console(stderr=True),
    )
    bar.start()
    return bar, bar.add_task("drive", total=total_m)


def drive_bound_s(route: Route) -> float:
    """Simulated seconds a drive of ``route`` takes at most: the rest, the give-up time and the
    tail."""
    return REST_S + TIMEOUT_FACTOR * route_length_m(route) / route.max_speed_m_s + TAIL_S


def check_route(cfg: TwinConfig, route: Route) -> None:
    """Refuse, before any drive, a route whose drive could take more than ``MAX_RUN_S`` simulated s
    or that leaves its world's free space (:func:`amr_twin.controllers.route.check_in_free_space`);
    RouteError."""
    from amr_twin.controllers.route import RouteError, check_in_free_space
    from amr_twin.model.world_spec import world_model
    from amr_twin.sim.bounds import MAX_RUN_S

    bound = drive_bound_s(route)
    if bound > MAX_RUN_S:
        raise RouteError(
            f"route {route.name}: {route_length_m(route):.0f} m at up to {route.max_speed_m_s:g} "
            f"m/s may take {bound:.0f} s of simulation ({TIMEOUT_FACTOR:g} x length / speed before "
            f"it gives up); at most {MAX_RUN_S:g} s: a shorter route or a higher max_speed_m_s"
        )
    model = world_model(cfg, route.world)
    top_m = float(cfg.components.lidar.pos_m[2])  # the robot's highest part
    slices = [scan_plane_boxes(model, z) for z in [*np.arange(0.02, top_m, 0.05), top_m]]
    keep = {}
    for cut in slices:  # every geom the robot's height meets, once
        for i, name in enumerate(cut.names):
            keep.setdefault(name, (cut.centre_xy_m[i], cut.half_xy_m[i], cut.yaw_rad[i]))
    boxes = Footprints(
        np.array([v[0] for v in keep.values()]).reshape(-1, 2),
        np.array([v[1] for v in keep.values()]).reshape(-1, 2),
        np.array([v[2] for v in keep.values()]),
        tuple(keep),
    )
    check_in_free_space(route, boxes, cfg.half_width_m, world=route.world)


def route_file(route: str | Path | None) -> Path:
    """The file of ``--route``: None is the default route, a bare name one of
    ``experiments/routes/``."""
    if route is None:
        return DEFAULT_ROUTE
    path = Path(route)
    if not path.suffix and not path.exists():
        return ROUTES_DIR / f"{route}.yaml"
    return path


def route_names() -> list[str]:
    """The routes that come with the twin (``experiments/routes/*.yaml``)."""
    return sorted(p.stem for p in ROUTES_DIR.glob("*.yaml"))


def site_config(cfg: TwinConfig, route: Route) -> TwinConfig:
    """``cfg`` with the UWB anchors of the route's world, when the world declares its own."""
    from amr_twin.model.worlds import uwb_anchors_xy_m

    anchors = uwb_anchors_xy_m(route.world)
    if anchors is None:
        return cfg
    uwb = cfg.uwb.model_copy(
        update={
            "anchors_x_m": tuple(float(v) for v in anchors[:, 0]),
            "anchors_y_m": tuple(float(v) for v in anchors[:, 1]),
        }
    )
    return cfg.model_copy(update={"uwb": uwb})


def run(
    cfg: TwinConfig,
    route_path: Path | str = DEFAULT_ROUTE,
    *,
    seed: int = 0,
    firmware: str = "improved",
    progress: bool = True,
    rrd_path: Path | None = None,
    mcap_path: Path | None = None,
    robot_errors: bool = True,
) -> FusionResults:
    """Drive the route, run the five architectures and score them against the truth.

    ``robot_errors``: the seed also draws the robot's own errors (:mod:`.robot`);
    False drives the robot exactly as its odometry assumes it.
    """
    route = load_route(route_path)
    check_route(cfg, route)
    cfg = site_config(cfg, route)
    robot = draw(cfg, seed) if robot_errors else NOMINAL
    t0 = time.perf_counter()
    twin, streams, reached = drive(
        cfg,
        route,
        seed=seed,
        firmware=firmware,
        progress=progress,
        rrd_path=rrd_path,
        mcap_path=mcap_path,
        robot=robot,
    )
    series = recorder_of(twin).series()
    res = FusionResults(
        route=route,
        seed=seed,
        firmware=firmware,
        t_true_s=series.t_s,
        pose_true=series.pose,
        streams=streams,
        sim_s=twin.t_s,
        drive_wall_s=time.perf_counter() - t0,
        reached_goal=reached,
        message_counts=streams.counts(),
    )
    res.cross_track_rms_m = float(
        np.sqrt(np.mean(distance_to_path_m(route, series.pose[:, :2]) ** 2))
    )
    uwb = twin.sensors["uwb"]
    res.uwb_blocked = uwb.blocked.tolist()
    res.uwb_exchanges = int(uwb.exchanges)
    gyro = twin.sensors["imu"].models["gyro"]
    res.robot = {
        **robot.as_dict(cfg),
        "drawn": bool(robot_errors),
        "gyro_scale_z": float(gyro.scale[2]),
    }
    start = route.start_xy_yaw
    jobs = (  # in the order of ARCHITECTURES
        lambda: estimate_odom(streams, start),
        lambda: estimate_lidar(cfg, streams, start),
        lambda: estimate_ekf(cfg, streams, start, use_imu=True, use_uwb=False),
        lambda: estimate_ekf(cfg, streams, start, use_imu=False, use_uwb=True),
        lambda: estimate_ekf(cfg, streams, start, use_imu=True, use_uwb=True),
    )
    for job in jobs:
        t1 = time.perf_counter()
        est = job()
        est.wall_s = time.perf_counter() - t1
        est.t_s, est.pose = last_per_stamp(est.t_s, est.pose)
        est.errors = errors(est.t_s, est.pose, series.t_s, series.pose, rpe_delta_m=RPE_DELTA_M)
        est.ate_aligned_m = errors(
            est.t_s, est.pose, series.t_s, series.pose, rpe_delta_m=RPE_DELTA_M, align=True
        ).ate_m
        res.estimates[est.name] = est
    res.anchors_xy_m = np.asarray(cfg.uwb.anchors_xy_m, float).reshape(-1, 2)
    res.boxes = scan_plane_boxes(
        twin.physics.model, float(twin.physics.site_position_m("amr/laser")[2])
    )
    res.grid = build_map(
        streams.scan,
        res.estimates["odom+lidar"].beam_poses,
        res.boxes,
        cfg.mapping.resolution_m,
        cfg.mapping.margin_m,
    )
    res.wall_s = time.perf_counter() - t0
    return res
