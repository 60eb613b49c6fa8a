"""The SLAM map of the navigation experiment: the robot drives every aisle once, its scans make the map.

The fusion experiment's pipeline (:mod:`.fusion`): a pure-pursuit drive of a route through every
aisle of the world (``experiments/routes/<world>_mapping.yaml``) with the LiDAR, IMU and UWB on,
then the scans inserted into a log-odds grid (controllers/occupancy_grid.py), each beam at the
laser pose of its own instant, saved as map_server YAML + PGM. The poses are the EKF's (odometry,
gyro and UWB: :func:`.fusion.estimate_ekf`), not kiss-icp's: LiDAR odometry has no loop closure and
drifts over a few hundred metres of look-alike aisles, while the UWB keeps the map frame to a few
cm. The EKF's heading wanders by a fraction of a degree, which drew rows twice and slanted; each
scan is therefore matched to the map of the scans before it (:mod:`.navigation_scan_match`, a
SLAM front end's scan matcher) before the grid is made; a ROS user would get a comparable map from
slam_toolbox, which adds loop closures. What the map holds is
what the scan plane (0.45 m) cuts: loose pallets lower than that are not on it (a collision risk the
experiment reports, not one it hides). Its agreement with the world is measured as the fusion
experiment's (:func:`.fusion_map.agreement`).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from amr_twin.experiments.fusion import ROUTES_DIR

MAPPING_ROUTE = "{world}_mapping.yaml"


def mapping_route(world: str) -> Path:
    """The route that maps ``world`` (a file of experiments/routes/); ValueError naming it if there is none."""
    path = ROUTES_DIR / MAPPING_ROUTE.format(world=world)
    if not path.is_file():
        raise ValueError(f"world {world}: no mapping route ({path.name} in experiments/routes/); give --slam-map")
    return path


def build_slam_map(cfg, world: str, stem: Path, seed: int = 0, progress: bool = False) -> dict:
    """Drive the mapping route, build the map from the EKF's poses matched scan to map (:func:`save_slam_map`),
    save ``<stem>.yaml/.pgm/.png``; its figures."""
    from amr_twin.analysis import se2
    from amr_twin.controllers.lidar_odometry import beam_times_s
    from amr_twin.controllers.route import load_route
    from amr_twin.experiments.fusion import drive, estimate_ekf, laser_in_base, site_config
    from amr_twin.model.world_geometry import scan_plane_boxes

    route = load_route(mapping_route(world))
    cfg = site_config(cfg, route)
    twin, streams, reached = drive(cfg, route, seed=seed, firmware="improved", progress=progress)
    est = estimate_ekf(cfg, streams, route.start_xy_yaw, use_imu=True, use_uwb=True)
    t, pose = est.t_s, est.pose
    keep = np.append(t[1:] != t[:-1], True)
    t, pose = t[keep], pose[keep]
    laser = np.asarray(laser_in_base(cfg))
    beam_poses = [se2.compose(se2.interpolate(t, pose, beam_times_s(scan)).reshape(-1, 3), laser)
                  for scan in streams.scan]
    boxes = scan_plane_boxes(twin.physics.model, float(twin.physics.site_position_m("amr/laser")[2]))
    return save_slam_map(streams.scan, beam_poses, boxes, cfg, stem) | {
        "route": route.name, "reached": bool(reached), "drive_sim_s": twin.t_s}


def save_slam_map(scans: list, beam_poses: list, boxes, cfg, stem: Path) -> dict:
    """The map of ``scans`` at ``beam_poses`` (the EKF's) after scan-to-map matching
    (:mod:`.navigation_scan_match`), saved at ``stem``; its agreement with the world (``boxes``), and
    that of the map the EKF's poses alone make (``ekf_only_*``, not saved)."""
    from amr_twin.experiments.fusion_map import agreement, build_map
    from amr_twin.experiments.navigation_scan_match import match_scans

    res, margin = cfg.mapping.resolution_m, cfg.mapping.margin_m
    plain = build_map(scans, beam_poses, boxes, res, margin)
    matched, corrections = match_scans(scans, beam_poses, plain.origin_xy_m, (plain.n_rows, plain.n_cols), res)
    grid = build_map(scans, matched, boxes, res, margin)
    yaml_path, _, png = grid.save(stem)
    check = agreement(yaml_path, boxes)
    plain_yaml, _, _ = plain.save(Path(str(stem) + "_ekf_only"))
    before = agreement(plain_yaml, boxes)
    for suffix in (".yaml", ".pgm", ".png"):
        plain_yaml.with_suffix(suffix).unlink(missing_ok=True)
    return {"yaml": str(yaml_path), "png": str(png), "scans": len(scans),
            "walls_within_2_cells_frac": check.within_tolerance_frac, "outline_seen_frac": check.outline_seen_frac,
            "p95_distance_cells": check.p95_distance_cells,
            "ekf_only_walls_within_2_cells_frac": before.within_tolerance_frac,
            "ekf_only_p95_distance_cells": before.p95_distance_cells,
            "correction_p95": [float(v) for v in np.percentile(np.abs(corrections), 95, axis=0)]}
