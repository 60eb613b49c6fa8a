"""One fusion drive's metrics as typed records, and ``metrics.json`` written from them.

:func:`metrics` gathers a :class:`~amr_twin.experiments.fusion.results.FusionResults` (the drive,
each architecture's trajectory errors), the saved map's check and the TUM file names into a
:class:`FusionMetrics`; :meth:`FusionMetrics.as_json` is the ``metrics.json`` object. Distances in
metres, angles in degrees, times in seconds.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass
from typing import Optional

from amr_twin.analysis.trajectory import TrajectoryErrors
from amr_twin.experiments.fusion.experiment import ARCHITECTURES, RPE_DELTA_M
from amr_twin.experiments.fusion.results import FusionResults
from amr_twin.experiments.fusion.map import TOLERANCE_CELLS, MapAgreement

LIDAR_ATE_MAX_M = 0.10  # the fusion acceptance


@dataclass(frozen=True)
class RouteOutcome:
    """The route driven: its name and world, its true length m, the speed limit m/s, whether the
    goal was reached and the RMS cross-track error m of the true path against the route."""

    name: str
    world: str
    length_m: float
    max_speed_m_s: float
    reached_goal: bool
    cross_track_rms_m: float


@dataclass(frozen=True)
class UwbOutcome:
    """The UWB anchors (K, 2) m in the map frame, the ranging exchanges made, and per anchor those
    whose line of sight a wall blocked."""

    anchors_xy_m: list
    exchanges: int
    blocked_per_anchor: Optional[list]


@dataclass(frozen=True)
class ArchitectureMetrics:
    """One architecture's trajectory errors against the truth, its ATE after SE(2) alignment m, the
    CPU wall time of its estimator s and its TUM file's name."""

    errors: TrajectoryErrors
    ate_aligned_m: float
    wall_s: float
    tum: str

    def as_json(self) -> dict:
        return {
            **asdict(self.errors),
            "ate_aligned_m": self.ate_aligned_m,
            "wall_s": self.wall_s,
            "tum": self.tum,
        }


@dataclass(frozen=True)
class FusionVerdicts:
    """The fusion acceptance verdicts: the odometry's final drift m and % of the route, the IMU
    improving the heading, the LiDAR odometry's ATE under :data:`LIDAR_ATE_MAX_M`, the share of the
    map's walls within 2 cells, the goal reached."""

    odom_drift_final_m: float
    odom_drift_pct_of_length: float
    imu_beats_odom_on_heading: bool
    lidar_ate_under_0_10_m: bool
    map_walls_within_2_cells_frac: float
    reached_goal: bool


@dataclass(frozen=True)
class FusionMetrics:
    """Everything ``metrics.json`` holds: the route, the seed and firmware, simulated and wall
    seconds (the drive's and in all), the messages per stream, the UWB, the robot's own errors of
    this seed, the RPE distance m, each architecture, the map check and the verdicts."""

    route: RouteOutcome
    seed: int
    firmware: str
    sim_s: float
    drive_wall_s: float
    wall_s: float
    messages: Optional[dict]
    uwb: UwbOutcome
    robot: Optional[dict]
    rpe_delta_m: float
    architectures: dict[str, ArchitectureMetrics]
    map_check: MapAgreement
    summary: FusionVerdicts

    def as_json(self) -> dict:
        return {
            "route": asdict(self.route),
            "seed": self.seed,
            "firmware": self.firmware,
            "sim_s": self.sim_s,
            "drive_wall_s": self.drive_wall_s,
            "wall_s": self.wall_s,
            "messages": self.messages,
            "uwb": asdict(self.uwb),
            "robot": self.robot,
            "rpe_delta_m": self.rpe_delta_m,
            "architectures": {name: a.as_json() for name, a in self.architectures.items()},
            "map": {"tolerance_cells": TOLERANCE_CELLS, **asdict(self.map_check)},
            "summary": asdict(self.summary),
        }


def verdicts(results: FusionResults, map_check: MapAgreement) -> FusionVerdicts:
    """The fusion acceptance verdicts on this run."""
    e = {name: results.estimates[name].errors for name in ARCHITECTURES}
    return FusionVerdicts(
        odom_drift_final_m=e["odom"].final_pos_err_m,
        odom_drift_pct_of_length=100.0 * e["odom"].final_pos_err_m / max(e["odom"].length_m, 1e-9),
        imu_beats_odom_on_heading=e["odom+imu"].rms_yaw_err_deg < e["odom"].rms_yaw_err_deg,
        lidar_ate_under_0_10_m=e["odom+lidar"].ate_m < LIDAR_ATE_MAX_M,
        map_walls_within_2_cells_frac=map_check.within_tolerance_frac,
        reached_goal=results.reached_goal,
    )


def metrics(
    results: FusionResults, map_check: MapAgreement, files: dict[str, str]
) -> FusionMetrics:
    """The typed metrics of one drive; ``files``: each architecture's TUM file name."""
    est = results.estimates
    return FusionMetrics(
        route=RouteOutcome(
            results.route.name,
            results.route.world,
            est["odom"].errors.length_m,
            results.route.max_speed_m_s,
            results.reached_goal,
            results.cross_track_rms_m,
        ),
        seed=results.seed,
        firmware=results.firmware,
        sim_s=results.sim_s,
        drive_wall_s=results.drive_wall_s,
        wall_s=results.wall_s,
        messages=results.message_counts,
        uwb=UwbOutcome(results.anchors_xy_m.tolist(), results.uwb_exchanges, results.uwb_blocked),
        robot=results.robot,
        rpe_delta_m=RPE_DELTA_M,
        architectures={
            name: ArchitectureMetrics(
                est[name].errors, est[name].ate_aligned_m, est[name].wall_s, files[name]
            )
            for name in ARCHITECTURES
        },
        map_check=map_check,
        summary=verdicts(results, map_check),
    )
