"""The SLAM map of the navigation experiment: the robot drives every aisle once, its scans make the map.

The fusion experiment's pipeline (:mod:`.fusion`): a pure-pursuit drive of a route through every
aisle of the world (``experiments/routes/<world>_mapping.yaml``) with the LiDAR, IMU and UWB on,
then the scans inserted into a log-odds grid (controllers/occupancy_grid.py), each beam at the
laser pose of its own instant, saved as map_server YAML + PGM. The poses are the EKF's (odometry,
gyro and UWB: :func:`.fusion.estimate_ekf`), not kiss-icp's: LiDAR odometry has no loop closure and
drifts over a few hundred metres of look-alike aisles, while the UWB keeps the map frame to a few
cm; a ROS user would get a comparable map from slam_toolbox's loop closures. What the map holds is
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
    """Drive the mapping route, build the map from the EKF's poses, save ``<stem>.yaml/.pgm/.png``; its figures."""
    from amr_twin.analysis import se2
    from amr_twin.controllers.lidar_odometry import beam_times_s
    from amr_twin.controllers.route import load_route
    from amr_twin.experiments.fusion import drive, estimate_ekf, laser_in_base, site_config
    from amr_twin.experiments.fusion_map import agreement, build_map
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
    grid = build_map(streams.scan, beam_poses, boxes, cfg.mapping.resolution_m, cfg.mapping.margin_m)
    yaml_path, _, png = grid.save(stem)
    check = agreement(yaml_path, boxes)
    return {"yaml": str(yaml_path), "png": str(png), "route": route.name, "reached": bool(reached),
            "drive_sim_s": twin.t_s, "scans": len(streams.scan),
            "walls_within_2_cells_frac": check.within_tolerance_frac, "outline_seen_frac": check.outline_seen_frac,
            "p95_distance_cells": check.p95_distance_cells}
