"""The SLAM map of the navigation experiment: the robot drives every aisle once, its scans make the
map.

The fusion experiment's pipeline (:mod:`.fusion.experiment`): a pure-pursuit drive of a route
through every aisle of the world (``experiments/routes/<world>_mapping.yaml``) with the LiDAR, IMU
and UWB on, then the scans inserted into a log-odds grid (amr_twin/estimation/occupancy_grid.py),
each beam at the laser pose of its own instant, saved as map_server YAML + PGM. The poses are
smoothed over the whole drive (amr_twin/estimation/pose_graph.py, GTSAM): kiss-icp's and the wheel
odometry's motion between scans and every UWB range, the ranges late behind racks weighed down.
Neither a filter nor LiDAR odometry alone makes a straight map there: the EKF's heading wanders
where the ranges are late (0.6-0.8 deg median, up to 7 deg), which drew rows twice and slanted, and
kiss-icp slides 1-1.5 m along look-alike aisles. Each scan is then matched to the map of the scans
before it (:mod:`.scan_match`, a SLAM front end's scan matcher) before the grid is made; a ROS user
would get a comparable map from slam_toolbox with loop closures. What the map holds is what the
scan plane (0.45 m) cuts: loose pallets lower than that are not on it (a collision risk the
experiment reports, not one it hides). Its agreement with the world is measured as the fusion
experiment's (:func:`.fusion.map.agreement`), and so is that of the map the EKF's poses would make
(``ekf_only_*``).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from amr_twin.experiments.fusion.experiment import ROUTES_DIR

MAPPING_ROUTE = "{world}_mapping.yaml"


def mapping_route(world: str) -> Path:
    """The route that maps ``world`` (a file of experiments/routes/); ValueError naming it if there
    is none."""
    path = ROUTES_DIR / MAPPING_ROUTE.format(world=world)
    if not path.is_file():
        raise ValueError(
            f"world {world}: no mapping route ({path.name} in experiments/routes/); give --slam-map"
        )
    return path


def build_slam_map(cfg, world: str, stem: Path, seed: int = 0, progress: bool = False) -> dict:
    """Drive the mapping route, smooth its poses, build the map matched scan to map
    (:func:`save_slam_map`), save ``<stem>.yaml/.pgm/.png``; its figures."""
    from amr_twin.estimation.pose_graph import smooth
    from amr_twin.controllers.route import load_route
    from amr_twin.experiments.fusion.estimators import estimate_ekf, estimate_lidar, last_per_stamp
    from amr_twin.experiments.fusion.experiment import drive, site_config
    from amr_twin.experiments.fusion.streams import odom_poses
    from amr_twin.model.world_geometry import scan_plane_boxes

    route = load_route(mapping_route(world))
    cfg = site_config(cfg, route)
    twin, streams, reached = drive(cfg, route, seed=seed, firmware="improved", progress=progress)
    lidar = estimate_lidar(cfg, streams, route.start_xy_yaw)
    lidar_t, lidar_pose = last_per_stamp(lidar.t_s, lidar.pose)
    odom_t, odom_pose = odom_poses(streams.odom)
    tag = cfg.uwb.tag_pos_m
    smoothed = smooth(
        lidar_t,
        lidar_pose,
        odom_t,
        odom_pose,
        streams.uwb,
        cfg.uwb.anchors_xy_m,
        tag[:2],
        cfg.uwb.anchor_z_m - tag[2],
        lidar_pose[0],
        cfg.ekf.uwb_range_sigma_m,
        cfg.mapping.pose_graph,
    )
    ekf = estimate_ekf(cfg, streams, route.start_xy_yaw, use_imu=True, use_uwb=True)
    boxes = scan_plane_boxes(
        twin.physics.model, float(twin.physics.site_position_m("amr/laser")[2])
    )
    return save_slam_map(
        streams.scan,
        beam_poses(cfg, streams.scan, smoothed.t_s, smoothed.pose),
        boxes,
        cfg,
        stem,
        ekf_beam_poses=beam_poses(cfg, streams.scan, ekf.t_s, ekf.pose),
    ) | {
        "route": route.name,
        "reached": bool(reached),
        "drive_sim_s": twin.t_s,
        "pose_graph": {
            "ranges_used": smoothed.ranges_used,
            "ranges_left_out": smoothed.ranges_left_out,
            "iterations": smoothed.iterations,
            "error_before": smoothed.error_before,
            "error_after": smoothed.error_after,
        },
    }


def beam_poses(cfg, scans: list, t_s: np.ndarray, pose: np.ndarray) -> list:
    """Per scan, the laser pose (n_beams, 3) at each beam's instant, from base poses (N, 3) at
    ``t_s`` (N,) (the last of equal stamps kept)."""
    from amr_twin.analysis import se2
    from amr_twin.estimation.lidar_odometry import beam_times_s
    from amr_twin.experiments.fusion.estimators import laser_in_base, last_per_stamp

    t_s, pose = last_per_stamp(t_s, pose)
    laser = np.asarray(laser_in_base(cfg))
    return [
        se2.compose(se2.interpolate(t_s, pose, beam_times_s(scan)).reshape(-1, 3), laser)
        for scan in scans
    ]


def save_slam_map(
    scans: list, beam_poses: list, boxes, cfg, stem: Path, ekf_beam_poses: list | None = None
) -> dict:
    """The map of ``scans`` at ``beam_poses`` after scan-to-map matching (:mod:`.scan_match`),
    saved at ``stem``; its agreement with the world (``boxes``), and that of the maps the poses make
    unmatched (``unmatched_*``) and the EKF's poses make (``ekf_only_*``, when given; neither
    saved)."""
    from amr_twin.experiments.fusion.map import agreement, build_map
    from amr_twin.experiments.navigation.scan_match import match_scans

    res, margin = cfg.mapping.resolution_m, cfg.mapping.margin_m
    plain = build_map(scans, beam_poses, boxes, res, margin)
    matched, corrections = match_scans(
        scans, beam_poses, plain.origin_xy_m, (plain.n_rows, plain.n_cols), res
    )
    grid = build_map(scans, matched, boxes, res, margin)
    yaml_path, _, png = grid.save(stem)
    check = agreement(yaml_path, boxes)
    out = {
        "yaml": str(yaml_path),
        "png": str(png),
        "scans": len(scans),
        "walls_within_2_cells_frac": check.within_tolerance_frac,
        "outline_seen_frac": check.outline_seen_frac,
        "p95_distance_cells": check.p95_distance_cells,
        "correction_p95": [float(v) for v in np.percentile(np.abs(corrections), 95, axis=0)],
    }
    others = {"unmatched": plain}
    if ekf_beam_poses is not None:
        others["ekf_only"] = build_map(scans, ekf_beam_poses, boxes, res, margin)
    for name, other in others.items():
        other_yaml, _, _ = other.save(Path(f"{stem}_{name}"))
        a = agreement(other_yaml, boxes)
        for suffix in (".yaml", ".pgm", ".png"):
            other_yaml.with_suffix(suffix).unlink(missing_ok=True)
        out |= {
            f"{name}_walls_within_2_cells_frac": a.within_tolerance_frac,
            f"{name}_p95_distance_cells": a.p95_distance_cells,
        }
    return out
