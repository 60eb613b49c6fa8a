"""Offline pose-graph smoothing of a drive: LiDAR and wheel odometry between scans, UWB ranges to
the anchors.

Reasons and measurements: docs/explanation/fusion.md#amr_twinestimationpose_graph."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from amr_twin.analysis import se2
from amr_twin.model.config_estimation import PoseGraphCfg
from amr_twin.sensors.uwb import anchor_index

ANCHOR_KEY = 10**7  # key of anchor 0; poses are keyed 0..N-1
ANCHOR_SIGMA_M = 1e-4
MIN_RANGE_OVER_DZ = 1.05


@dataclass(frozen=True)
class SmoothedTrajectory:
    """What :func:`smooth` returns: the stamps (N,) s and poses (N, 3) in the map frame, the ranges
    used and left out, the Levenberg-Marquardt iterations and the graph's error before and after."""

    t_s: np.ndarray
    pose: np.ndarray
    ranges_used: int
    ranges_left_out: int
    iterations: int
    error_before: float
    error_after: float


def _pose2(p):
    import gtsam

    return gtsam.Pose2(float(p[0]), float(p[1]), float(p[2]))


def _range_factors(
    graph, t_s, odom_t_s, odom_pose, ranges, anchor, tag_xy_m, dz_m, sigma_m, cauchy_k
) -> int:
    """Add a robust range factor per usable ``sensor_msgs/Range`` (module notes), ``anchor`` (M,)
    the index of each one's anchor; how many were added."""
    import gtsam

    stamps = np.array([m.header.stamp.to_sec() for m in ranges], float)
    z = np.array([m.range for m in ranges], float)
    with np.errstate(invalid="ignore"):
        ok = (
            np.isfinite(z)
            & (stamps >= t_s[0])
            & (stamps <= t_s[-1])
            & (z > MIN_RANGE_OVER_DZ * dz_m)
        )
    idx = np.flatnonzero(ok)
    if not len(idx):
        return 0
    k = np.clip(np.searchsorted(t_s, stamps[idx]), 1, len(t_s) - 1)
    k = np.where(stamps[idx] - t_s[k - 1] < t_s[k] - stamps[idx], k - 1, k)
    at_node = se2.interpolate(odom_t_s, odom_pose, t_s[k]).reshape(-1, 3)
    at_range = se2.interpolate(odom_t_s, odom_pose, stamps[idx]).reshape(-1, 3)
    sensor = se2.compose(se2.between(at_node, at_range), np.array([tag_xy_m[0], tag_xy_m[1], 0.0]))
    horizontal = np.sqrt(z[idx] ** 2 - dz_m**2)
    robust = gtsam.noiseModel.mEstimator.Cauchy.Create(cauchy_k)
    for j, i in enumerate(idx):
        noise = gtsam.noiseModel.Robust.Create(
            robust, gtsam.noiseModel.Isotropic.Sigma(1, sigma_m * z[i] / horizontal[j])
        )
        graph.add(
            gtsam.RangeFactorWithTransform2D(
                int(k[j]),
                ANCHOR_KEY + int(anchor[i]),
                float(horizontal[j]),
                noise,
                _pose2(sensor[j]),
            )
        )
    return len(idx)


def smooth(
    t_s: np.ndarray,
    lidar_pose: np.ndarray,
    odom_t_s: np.ndarray,
    odom_pose: np.ndarray,
    ranges: list,
    anchors_xy_m: np.ndarray,
    tag_xy_m,
    dz_m: float,
    start_pose,
    range_sigma_m: float,
    cfg: PoseGraphCfg,
) -> SmoothedTrajectory:
    """Smooth a drive (module notes).

    ``t_s`` (N,), ``lidar_pose`` (N, 3): kiss-icp's poses at the scans' ends, in the map frame;
    ``odom_t_s`` (M,), ``odom_pose`` (M, 3): the wheel odometry (any fixed frame); ``ranges``: the
    drive's ``sensor_msgs/Range`` messages (frame ``uwb_anchor_<i>``); ``anchors_xy_m`` (K, 2);
    ``tag_xy_m``: the tag on the base, m; ``dz_m``: the anchors' height above the tag;
    ``start_pose``: the prior of the first pose; ``range_sigma_m``: a line-of-sight range's sigma.
    """
    import gtsam

    t_s, lidar_pose = np.asarray(t_s, float), np.asarray(lidar_pose, float).reshape(-1, 3)
    n = len(t_s)
    if n < 2 or np.any(np.diff(t_s) <= 0):
        raise ValueError(f"t_s: {n} stamps; at least 2, strictly increasing")
    anchors = np.asarray(anchors_xy_m, float).reshape(-1, 2)
    graph, values = gtsam.NonlinearFactorGraph(), gtsam.Values()
    for k in range(n):
        values.insert(k, _pose2(lidar_pose[k]))
    graph.add(
        gtsam.PriorFactorPose2(
            0,
            _pose2(start_pose),
            gtsam.noiseModel.Diagonal.Sigmas(
                np.array([cfg.start_xy_sigma_m, cfg.start_xy_sigma_m, cfg.start_yaw_sigma_rad])
            ),
        )
    )
    lidar = gtsam.noiseModel.Diagonal.Sigmas(
        np.array([cfg.lidar_sigma_m, cfg.lidar_sigma_m, cfg.lidar_yaw_sigma_rad])
    )
    wheels = gtsam.noiseModel.Diagonal.Sigmas(
        np.array([cfg.odometry_sigma_m, cfg.odometry_sigma_m, cfg.odometry_yaw_sigma_rad])
    )
    odom_at = se2.interpolate(odom_t_s, odom_pose, t_s).reshape(-1, 3)
    lidar_step, odom_step = (
        se2.between(lidar_pose[:-1], lidar_pose[1:]),
        se2.between(odom_at[:-1], odom_at[1:]),
    )
    for k in range(n - 1):
        graph.add(gtsam.BetweenFactorPose2(k, k + 1, _pose2(lidar_step[k]), lidar))
        graph.add(gtsam.BetweenFactorPose2(k, k + 1, _pose2(odom_step[k]), wheels))
    anchor_noise = gtsam.noiseModel.Isotropic.Sigma(2, ANCHOR_SIGMA_M)
    for a, xy in enumerate(anchors):
        values.insert(ANCHOR_KEY + a, gtsam.Point2(*xy))
        graph.add(gtsam.PriorFactorPoint2(ANCHOR_KEY + a, gtsam.Point2(*xy), anchor_noise))
    anchor = np.array([anchor_index(m.header.frame_id) for m in ranges], int)
    if np.any(anchor >= len(anchors)):
        bad = ranges[int(np.argmax(anchor >= len(anchors)))].header.frame_id
        raise ValueError(f"uwb/range: {bad} is not one of the {len(anchors)} anchors")
    used = _range_factors(
        graph,
        t_s,
        odom_t_s,
        odom_pose,
        ranges,
        anchor,
        tag_xy_m,
        dz_m,
        range_sigma_m,
        cfg.uwb_cauchy_k,
    )
    params = gtsam.LevenbergMarquardtParams()
    params.setMaxIterations(cfg.max_iterations)
    optimizer = gtsam.LevenbergMarquardtOptimizer(graph, values, params)
    before = graph.error(values)
    result = optimizer.optimize()
    pose = np.array(
        [
            [result.atPose2(k).x(), result.atPose2(k).y(), result.atPose2(k).theta()]
            for k in range(n)
        ]
    )
    return SmoothedTrajectory(
        t_s,
        pose,
        used,
        len(ranges) - used,
        int(optimizer.iterations()),
        float(before),
        float(graph.error(result)),
    )
