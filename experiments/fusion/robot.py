"""The robot's own errors, drawn per seed: no two robots (and no two seeds) have the same odometry.

A real differential drive's odometry errs by its calibration as much as by noise: the tyres'
rolling radii differ from the nominal 0.125 m and from each other, the effective track from
the nominal 0.48 m, the hall sensors sit off their nominal places, and their edges jitter.
The odometry node and the cmd_vel node keep the nominal geometry (the thesis' listings,
uncalibrated); the physics rolls on the true one (``wheel.radius_error_*_m``,
``wheel.separation_error_m``, applied by :mod:`amr_twin.model.urdf`). The IMU's turn-on bias and
scale error are drawn by the IMU itself from the same seed (:mod:`amr_twin.sensors.imu`).

:func:`draw` takes each error from a normal with the sourced 1-sigma of ``models/amr/amr.yaml``
(``wheel.radius_tolerance_m``, ``separation_tolerance_m``, ``hall_misalignment_sigma_deg``),
clipped at 3 sigma, from its own stream of the seed (``default_rng([seed, 4])``): the same seed
gives the same robot. (A general sampler of every parameter's spread would draw these too;
this one draws only the errors an odometry study needs.)
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np

from amr_twin.model.config import TwinConfig

CLIP_SIGMA = 3.0
"""Draws are clipped at this many standard deviations (the sourced ranges' ends)."""
STREAM = 4
"""Index of the robot's stream of a seed (1 IMU, 2 LiDAR, 3 UWB)."""


@dataclass(frozen=True)
class RobotErrors:
    """One robot's errors: true minus nominal geometry, m; hall sensor offsets, deg of wheel
    angle."""

    radius_error_left_m: float = 0.0
    radius_error_right_m: float = 0.0
    separation_error_m: float = 0.0
    hall_misalignment_deg: tuple = (
        (0.0, 0.0, 0.0),
        (0.0, 0.0, 0.0),
    )  # (left, right) x (Ha, Hb, Hc)
    hall_jitter_us: float = 0.0

    def config(self, cfg: TwinConfig) -> TwinConfig:
        """``cfg`` with this robot's true wheel geometry (validated)."""
        wheel = cfg.wheel.model_dump()
        wheel.update(
            radius_error_left_m=self.radius_error_left_m,
            radius_error_right_m=self.radius_error_right_m,
            separation_error_m=self.separation_error_m,
        )
        return cfg.model_copy(update={"wheel": type(cfg.wheel).model_validate(wheel)})

    def twin_options(self) -> dict:
        """The :class:`~amr_twin.assembly.twin.TwinOptions` fields of the hall sensors."""
        return {
            "hall_misalignment_deg": np.asarray(self.hall_misalignment_deg, float),
            "hall_jitter_us": self.hall_jitter_us,
        }

    def as_dict(self, cfg: TwinConfig) -> dict:
        """JSON-ready values, and what they do to the nominal odometry (``cfg``: the nominal
        geometry).

        ``odom_distance_error``: odometry distance / true distance - 1 on a straight;
        ``odom_heading_drift_deg_per_m``: the odometry's heading error per metre of a
        straight; ``odom_turn_error``: odometry / true yaw - 1 of a turn in place.
        """
        r, b = cfg.wheel.radius_m, cfg.wheel.separation_m
        el, er = self.radius_error_left_m, self.radius_error_right_m
        d = asdict(self)
        d["hall_misalignment_deg"] = [list(row) for row in self.hall_misalignment_deg]
        d["odom_distance_error"] = r / (r + 0.5 * (el + er)) - 1.0
        d["odom_heading_drift_deg_per_m"] = float(
            np.degrees(r * (1.0 / (r + er) - 1.0 / (r + el)) / b)
        )
        d["odom_turn_error"] = (b + self.separation_error_m) / b - 1.0
        return d


NOMINAL = RobotErrors()
"""The robot exactly as the odometry assumes it."""


def _normal(rng: np.random.Generator, sigma: float, size=None):
    return np.clip(rng.standard_normal(size), -CLIP_SIGMA, CLIP_SIGMA) * sigma


def draw(cfg: TwinConfig, seed: int) -> RobotErrors:
    """The robot of ``seed``: each error from its sourced normal, clipped at :data:`CLIP_SIGMA`."""
    w = cfg.wheel
    rng = np.random.default_rng([int(seed), STREAM])
    left, right = (float(v) for v in _normal(rng, w.radius_tolerance_m, 2))
    separation = float(_normal(rng, w.separation_tolerance_m))
    hall = _normal(rng, w.hall_misalignment_sigma_deg, (2, 3))
    return RobotErrors(
        radius_error_left_m=left,
        radius_error_right_m=right,
        separation_error_m=separation,
        hall_misalignment_deg=tuple(tuple(float(v) for v in row) for row in hall),
        hall_jitter_us=float(w.hall_jitter_us),
    )
