"""The fusion experiment's five estimates of one recorded drive, each replayed offline on the same
streams: raw wheel odometry, kiss-icp LiDAR odometry and the EKF with the gyro, UWB or both
(thesis §6.2.2, figs. 6.4 to 6.7; the experiment: :mod:`.experiment`)."""

from __future__ import annotations

import numpy as np

from amr_twin.analysis import se2
from amr_twin.estimation.ekf import EkfNode
from amr_twin.estimation.lidar_odometry import LidarOdometry
from amr_twin.experiments.fusion.results import Estimate
from amr_twin.experiments.fusion.streams import Streams, odom_poses, relative_motion
from amr_twin.model.config import TwinConfig


def estimate_odom(streams: Streams, start: tuple[float, float, float]) -> Estimate:
    """Raw wheel odometry, moved from the ``odom`` frame into the map by the start pose."""
    t_s, pose = odom_poses(streams.odom)
    return Estimate("odom", t_s, se2.compose(np.asarray(start), pose))


def estimate_ekf(
    cfg: TwinConfig,
    streams: Streams,
    start: tuple[float, float, float],
    *,
    use_imu: bool,
    use_uwb: bool,
) -> Estimate:
    """Replay the streams in stamp order into an :class:`EkfNode`."""
    node = EkfNode(
        cfg.ekf,
        wheel_separation_m=cfg.wheel.separation_m,
        use_odom=True,
        use_imu=use_imu,
        use_uwb=use_uwb,
        uwb=cfg.uwb,
        initial_pose=start,
    )
    handlers = {"odom": node.on_odom, "imu": node.on_imu, "uwb": node.on_range}
    kinds = ("odom",) + (("imu",) if use_imu else ()) + (("uwb",) if use_uwb else ())
    for kind, msg in streams.merged(kinds):
        handlers[kind](msg)
    t_s, pose = node.history()
    name = "odom+" + "+".join(k for k in ("uwb", "imu") if k in kinds)
    return Estimate(name, np.asarray(t_s, float), np.asarray(pose, float))


def estimate_lidar(
    cfg: TwinConfig, streams: Streams, start: tuple[float, float, float]
) -> Estimate:
    """kiss-icp on every scan, with the wheel odometry's motion over each scan as the prior.

    kiss-icp deskews a scan to its last beam, so each pose holds at the scan's end
    (``t_end``) and the prior covers the interval between two scan ends
    (:meth:`LidarOdometry.prior_interval_s`). Returns the estimate in the map frame,
    with the laser pose at each beam's instant, per scan, in ``beam_poses`` (for the map).
    """
    lc = cfg.lidar_odometry
    lo = LidarOdometry(
        voxel_size_m=lc.voxel_size_m,
        max_range_m=lc.max_range_m,
        min_range_m=lc.min_range_m,
        laser_in_base_xy_yaw=laser_in_base(cfg),
        deskew=lc.deskew,
    )
    t_odom, pose_odom = odom_poses(streams.odom)
    for scan in streams.scan:
        t0, t1 = lo.prior_interval_s(scan)
        lo.register(scan, relative_motion(t_odom, pose_odom, t0, t1))
    t_s, _ = lo.poses()
    if len(t_s) == 0:
        return Estimate("odom+lidar", np.zeros(0), np.zeros((0, 3)), beam_poses=[])
    # the first pose is the origin of kiss-icp's frame: the start moved by the (rest) odometry up to
    # it
    origin = se2.compose(
        np.asarray(start, float), np.asarray(relative_motion(t_odom, pose_odom, 0.0, t_s[0]))
    )
    origin = tuple(float(v) for v in origin)
    _, pose = lo.poses(origin_xy_yaw=origin)
    beam_poses = [lo.beam_laser_poses(scan, origin_xy_yaw=origin) for scan in streams.scan]
    return Estimate("odom+lidar", t_s, pose, beam_poses=beam_poses)


def laser_in_base(cfg: TwinConfig) -> tuple[float, float, float]:
    """The ``laser`` frame in ``base_link``: x_m, y_m, yaw_rad (the mount of components.lidar)."""
    pos_m = cfg.components.lidar.pos_m
    return float(pos_m[0]), float(pos_m[1]), 0.0


def last_per_stamp(t_s: np.ndarray, pose: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Keep the last pose of each stamp: the estimate once every message of that instant is fused.

    A filter updated by two messages of one stamp (the odometry and the gyro on the 10 ms
    grid) records two poses there; a trajectory has one pose per instant (TUM tools pair
    poses by stamp).
    """
    t_s = np.asarray(t_s, float)
    if len(t_s) < 2:
        return t_s, pose
    keep = np.append(t_s[1:] != t_s[:-1], True)
    return t_s[keep], np.asarray(pose, float)[keep]
