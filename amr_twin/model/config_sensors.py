"""The sensors' sections of the parameter schema: the IMU (:class:`ImuCfg`), the LiDAR
(:class:`LidarCfg`) and UWB ranging (:class:`UwbCfg`), declared as
:mod:`amr_twin.model.config_sections` declares the robot's."""

from __future__ import annotations

from typing import Annotated

import numpy as np
from pydantic import Field, model_validator

from amr_twin.model.config_sections import P, PosVec3, Section, Vec3


class ImuCfg(Section):
    """Adafruit 9-DOF IMU: LSM303DLHC accelerometer/magnetometer + L3GD20 gyroscope (SI units)."""

    rate_hz: float = P(unit="Hz", ge=1.0, le=1000.0, setting=True)
    accel_range_m_s2: float = P(unit="m/s^2", gt=0.0, le=200.0, setting=True)
    accel_resolution_m_s2: float = P(unit="m/s^2", ge=0.0, le=1.0, setting=True)
    accel_noise_density_m_s2_sqrt_hz: float = P(unit="m/s^2/sqrt(Hz)", ge=0.0, le=0.1)
    accel_bias_sigma_m_s2: float = P(unit="m/s^2", ge=0.0, le=5.0)
    accel_bias_walk_m_s2_sqrt_s: float = P(unit="m/s^2/sqrt(s)", ge=0.0, le=0.1)
    accel_scale_sigma: float = P(unit="1", ge=0.0, le=0.1)
    gyro_range_rad_s: float = P(unit="rad/s", gt=0.0, le=100.0, setting=True)
    gyro_resolution_rad_s: float = P(unit="rad/s", ge=0.0, le=0.1, setting=True)
    gyro_noise_density_rad_s_sqrt_hz: float = P(unit="rad/s/sqrt(Hz)", ge=0.0, le=0.1)
    gyro_bias_sigma_rad_s: float = P(unit="rad/s", ge=0.0, le=1.0)
    gyro_bias_walk_rad_s_sqrt_s: float = P(unit="rad/s/sqrt(s)", ge=0.0, le=0.01)
    gyro_scale_sigma: float = P(unit="1", ge=0.0, le=0.1)
    mag_range_t: float = P(unit="T", gt=0.0, le=1e-2, setting=True)
    mag_resolution_xy_t: float = P(unit="T", ge=0.0, le=1e-5, setting=True)
    mag_resolution_z_t: float = P(unit="T", ge=0.0, le=1e-5, setting=True)
    mag_noise_t: float = P(unit="T", ge=0.0, le=1e-4)
    mag_bias_sigma_t: float = P(unit="T", ge=0.0, le=1e-3)


class LidarCfg(Section):
    """Slamtec RPLIDAR A1 (A1M8) 2D scanner."""

    scan_rate_hz: float = P(unit="Hz", ge=1.0, le=10.0, setting=True)
    sample_rate_hz: int = P(unit="Hz", ge=2000, le=8000, setting=True)
    range_min_m: float = P(unit="m", gt=0.0, le=1.0)
    range_max_m: float = P(unit="m", gt=1.0, le=40.0)
    range_noise_frac: float = P(unit="1", ge=0.0, le=0.1)
    range_noise_floor_m: float = P(unit="m", ge=0.0, le=0.1)
    range_resolution_m: float = P(unit="m", ge=0.0, le=0.01, setting=True)

    @model_validator(mode="after")
    def _sample_rate_is_a_mode(self) -> "LidarCfg":
        if self.sample_rate_hz not in (2000, 4000, 8000):
            raise ValueError(
                "lidar.sample_rate_hz: must be 2000, 4000 or 8000 (A1 standard/express/boost)"
            )
        return self


_Coord = Annotated[float, Field(ge=-1000.0, le=1000.0)]


class UwbCfg(Section):
    """UWB two-way ranging (Decawave DW1000 / DWM1000 tag and anchors), SI units.

    The anchors stand in the world (``map``) frame at ``(anchors_x_m[i], anchors_y_m[i],
    anchor_z_m)``; the tag is at ``tag_pos_m`` in ``base_link``.
    """

    rate_hz: float = P(unit="Hz", ge=0.5, le=100.0, setting=True)
    range_noise_sigma_m: float = P(unit="m", ge=0.0, le=1.0)
    dropout_prob: float = P(unit="1", ge=0.0, le=0.9)
    nlos_prob: float = P(unit="1", ge=0.0, le=1.0)
    nlos_bias_m: float = P(unit="m", ge=0.0, le=10.0)
    blocked_bias_m: float = P(unit="m", ge=0.0, le=10.0)
    blocked_dropout_prob: float = P(unit="1", ge=0.0, le=1.0)
    max_range_m: float = P(unit="m", ge=1.0, le=300.0)
    anchors_x_m: tuple[_Coord, ...] = P(unit="m", setting=True)
    anchors_y_m: tuple[_Coord, ...] = P(unit="m", setting=True)
    anchor_z_m: float = P(unit="m", ge=0.0, le=30.0, setting=True)
    tag_pos_m: Vec3 = P(unit="m")
    tag_mass_kg: float = P(unit="kg", gt=0.0, le=1.0)
    tag_size_m: PosVec3 = P(unit="m")

    @model_validator(mode="after")
    def _anchors_paired(self) -> "UwbCfg":
        n = len(self.anchors_x_m)
        if n != len(self.anchors_y_m):
            raise ValueError(f"uwb.anchors_y_m: must have as many values as anchors_x_m ({n})")
        if not 3 <= n <= 16:
            raise ValueError(f"uwb.anchors_x_m: {n} anchors, allowed [3, 16] (2D position needs 3)")
        return self

    @property
    def anchors_xy_m(self):
        """Anchor positions in the world frame, ndarray shape (n_anchors, 2), m."""
        return np.column_stack((self.anchors_x_m, self.anchors_y_m)).astype(np.float64)
