"""The fusion experiment's typed result: one architecture's trajectory (:class:`Estimate`), the
drive with every estimate (:class:`FusionResults`, what :func:`.experiment.run` returns) and the
result slimmed to send between processes (:func:`slim`)."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from amr_twin.analysis.trajectory import TrajectoryErrors
from amr_twin.controllers.route import Route
from amr_twin.experiments.fusion.streams import Streams
from amr_twin.model.world_geometry import Footprints


@dataclass
class Estimate:
    """One architecture's trajectory: stamps (N,) s and poses (N, 3) x_m, y_m, yaw_rad in the map
    frame."""

    name: str
    t_s: np.ndarray
    pose: np.ndarray
    errors: TrajectoryErrors | None = None
    ate_aligned_m: float = float(
        "nan"
    )  # ATE after the least-squares SE(2) alignment onto the truth
    wall_s: float = 0.0
    beam_poses: list | None = (
        None  # LiDAR odometry only: per scan, (n_beams, 3) laser poses in the map
    )


@dataclass
class FusionResults:
    """What :func:`run` returns: the drive, the estimates and their errors."""

    route: Route
    seed: int
    firmware: str
    t_true_s: np.ndarray
    pose_true: np.ndarray
    streams: Streams
    estimates: dict[str, Estimate] = field(default_factory=dict)
    sim_s: float = 0.0
    drive_wall_s: float = 0.0
    wall_s: float = 0.0  # drive, estimators and map
    reached_goal: bool = False
    cross_track_rms_m: float = 0.0
    boxes: Footprints | None = None  # the world at the LiDAR's height
    grid: object = None  # OccupancyGrid from the LiDAR odometry's poses
    anchors_xy_m: np.ndarray | None = None  # UWB anchors (K, 2), map frame
    uwb_blocked: list | None = None  # per anchor: exchanges whose line a wall blocked
    uwb_exchanges: int = 0
    message_counts: dict | None = None  # messages per stream (kept when the streams are dropped)
    robot: dict | None = None  # the robot's own errors of this seed (fusion_robot), IMU's included


def slim(res: FusionResults) -> FusionResults:
    """``res`` without the recorded messages and the per-beam laser poses (to send it between
    processes)."""
    res.streams = Streams()
    for est in res.estimates.values():
        est.beam_poses = None
    return res
