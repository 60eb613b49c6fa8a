"""UMBmark: the return position errors of squares driven both ways, and the calibration from them.

Borenstein and Feng, "Measurement and correction of systematic odometry errors in mobile robots",
IEEE Trans. Robot. Autom. 12(6), 1996, reconstructed from its description (no code of theirs), in
REP-103 axes: start at the origin facing +x, a square of side ``L`` driven counter-clockwise (left
turns) and clockwise, each run's return position error ``e = true - odometry`` in the start's
frame (:class:`~amr_twin.experiments.umbmark.square.SquareRun`).

Reasons and measurements: docs/explanation/umbmark.md#amr_twinexperimentsumbmarkexperiment."""

from __future__ import annotations

import math
from dataclasses import dataclass

from amr_twin.controllers.odometry_calibration import OdometryCalibration


@dataclass(frozen=True)
class Cluster:
    """One direction's runs: centre of gravity of the return errors (m), its distance from the
    origin ``r_cg_m``, and the runs' spread about it: RMS and largest distance (m)."""

    direction: str
    n: int
    x_cg_m: float
    y_cg_m: float
    r_cg_m: float
    spread_rms_m: float
    spread_max_m: float


@dataclass(frozen=True)
class Umbmark:
    """UMBmark's figures from both directions' runs (module notes); angles in rad."""

    side_m: float
    cw: Cluster
    ccw: Cluster
    e_max_syst_m: float
    e_nonsyst_rms_m: float
    alpha_rad: float
    beta_rad: float
    e_d: float
    e_b: float


def cluster(direction: str, errors: list[tuple[float, float]]) -> Cluster:
    """The :class:`Cluster` of ``errors``, (x, y) return position errors in m."""
    if not errors:
        raise ValueError(f"UMBmark: no {direction} run")
    n = len(errors)
    x = sum(e[0] for e in errors) / n
    y = sum(e[1] for e in errors) / n
    d = [math.hypot(e[0] - x, e[1] - y) for e in errors]
    return Cluster(
        direction, n, x, y, math.hypot(x, y), math.sqrt(sum(v * v for v in d) / n), max(d)
    )


def umbmark(
    cw: list[tuple[float, float]],
    ccw: list[tuple[float, float]],
    side_m: float,
    separation_m: float,
) -> Umbmark:
    """UMBmark of the clockwise and counter-clockwise runs' return errors (m) on a square of
    ``side_m``, for a robot of nominal wheelbase ``separation_m``."""
    a, b = cluster("cw", cw), cluster("ccw", ccw)
    four_l = 4.0 * side_m
    alpha = 0.5 * ((a.x_cg_m + b.x_cg_m) / four_l + (a.y_cg_m - b.y_cg_m) / four_l)
    beta = 0.5 * ((b.x_cg_m - a.x_cg_m) / four_l - (a.y_cg_m + b.y_cg_m) / four_l)
    if beta == 0.0:
        e_d = 1.0
    else:
        radius = (side_m / 2.0) / math.sin(beta / 2.0)
        e_d = (radius + separation_m / 2.0) / (radius - separation_m / 2.0)
    e_b = 90.0 / (90.0 + math.degrees(alpha))
    return Umbmark(
        side_m,
        a,
        b,
        max(a.r_cg_m, b.r_cg_m),
        max(a.spread_rms_m, b.spread_rms_m),
        alpha,
        beta,
        e_d,
        e_b,
    )


def calibration(
    result: Umbmark, base: OdometryCalibration, source: str = ""
) -> OdometryCalibration:
    """The odometry's geometry corrected by ``result`` (``base``: the geometry the runs were driven
    with)."""
    c_l = 2.0 / (result.e_d + 1.0)
    c_r = 2.0 / (1.0 / result.e_d + 1.0)
    return OdometryCalibration(
        base.left_wheel_radius_m * c_l,
        base.right_wheel_radius_m * c_r,
        base.wheel_separation_m * result.e_b,
        source,
    )
