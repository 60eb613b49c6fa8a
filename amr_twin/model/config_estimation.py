"""The estimators' sections of the parameter schema: the EKF (:class:`EkfCfg`), kiss-icp
(:class:`LidarOdometryCfg`), the mapping drive's occupancy grid and smoother
(:class:`MappingCfg`, :class:`PoseGraphCfg`); settings, declared as
:mod:`amr_twin.model.config_sections` declares the robot's."""

from __future__ import annotations

from typing import ClassVar

from pydantic import model_validator

from amr_twin.model.config_sections import P, Section


class EkfCfg(Section):
    """EKF of ``amr_twin/estimation/ekf.py`` (robot_localization ``ekf_node`` in two_d_mode), SI
    units.

    Process noise is white acceleration; measurement sigmas are those the filter
    assumes (not the simulated sensors' own), the Mahalanobis gate is in sigmas.
    """

    SETTINGS: ClassVar[bool] = True

    accel_sigma_m_s2: float = P(unit="m/s^2", gt=0.0, le=20.0)
    alpha_sigma_rad_s2: float = P(unit="rad/s^2", gt=0.0, le=50.0)
    gyro_bias_walk_rad_s_sqrt_s: float = P(unit="rad/s/sqrt(s)", ge=0.0, le=0.1)
    odom_v_sigma_m_s: float = P(unit="m/s", gt=0.0, le=5.0)
    odom_w_sigma_rad_s: float = P(unit="rad/s", gt=0.0, le=10.0)
    odom_differential: bool = P(unit="bool")
    gyro_w_sigma_rad_s: float = P(unit="rad/s", gt=0.0, le=10.0)
    uwb_range_sigma_m: float = P(unit="m", gt=0.0, le=10.0)
    initial_xy_sigma_m: float = P(unit="m", gt=0.0, le=100.0)
    initial_yaw_sigma_rad: float = P(unit="rad", gt=0.0, le=10.0)
    initial_v_sigma_m_s: float = P(unit="m/s", gt=0.0, le=10.0)
    initial_w_sigma_rad_s: float = P(unit="rad/s", gt=0.0, le=10.0)
    initial_gyro_bias_sigma_rad_s: float = P(unit="rad/s", gt=0.0, le=5.0)
    mahalanobis_gate: float = P(unit="1", gt=0.0, le=1000.0)
    imu_rest_calibration_s: float = P(unit="s", ge=0.0, le=60.0)
    rest_speed_m_s: float = P(unit="m/s", ge=0.0, le=0.5)


class LidarOdometryCfg(Section):
    """kiss-icp settings of ``amr_twin/estimation/lidar_odometry.py`` (plain keyword arguments)."""

    SETTINGS: ClassVar[bool] = True

    voxel_size_m: float = P(unit="m", ge=0.02, le=2.0)
    max_range_m: float = P(unit="m", gt=0.5, le=100.0)
    min_range_m: float = P(unit="m", ge=0.0, le=5.0)
    deskew: bool = P(unit="bool")

    @model_validator(mode="after")
    def _ranges_ordered(self) -> "LidarOdometryCfg":
        if self.min_range_m >= self.max_range_m:
            raise ValueError("lidar_odometry.min_range_m: must be less than max_range_m")
        return self


class PoseGraphCfg(Section):
    """The mapping drive's smoother (``amr_twin/estimation/pose_graph.py``): sigmas of its
    factors."""

    SETTINGS: ClassVar[bool] = True

    lidar_sigma_m: float = P(unit="m", gt=0.0, le=1.0)
    lidar_yaw_sigma_rad: float = P(unit="rad", gt=0.0, le=1.0)
    odometry_sigma_m: float = P(unit="m", gt=0.0, le=1.0)
    odometry_yaw_sigma_rad: float = P(unit="rad", gt=0.0, le=1.0)
    uwb_cauchy_k: float = P(unit="1", gt=0.0, le=100.0)
    start_xy_sigma_m: float = P(unit="m", gt=0.0, le=10.0)
    start_yaw_sigma_rad: float = P(unit="rad", gt=0.0, le=3.2)
    max_iterations: int = P(unit="1", ge=1, le=1000)


class MappingCfg(Section):
    """Occupancy grid of ``amr_twin/estimation/occupancy_grid.py`` and the mapping drive's
    smoother."""

    SETTINGS: ClassVar[bool] = True

    resolution_m: float = P(unit="m", ge=0.01, le=1.0)
    margin_m: float = P(unit="m", ge=0.0, le=20.0)
    pose_graph: PoseGraphCfg
