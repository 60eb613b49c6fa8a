"""The ``navigation:`` section of the parameter file: the settings of the navigation stack.

Not the robot: the speeds and ramps the navigation asks for (inside the firmware's limits), the
costmaps, the planner, the MPPI controller, the collision monitor, the people tracker, the progress
checker and the recoveries (:mod:`amr_twin.navigation`; the stack builds each part from its
subsection, field names as the parts' keyword arguments). A section of settings
(:attr:`~amr_twin.model.config_sections.Section.SETTINGS`): the uncertainty analysis never draws
them. Each field's unit and allowed range is here; its value, source (nav2's defaults where nav2
has the parameter) and sourced range are in ``models/amr/amr.yaml``. ``--set
navigation.mppi.samples=200`` overrides one as any other parameter.
"""

from __future__ import annotations

from typing import ClassVar

from pydantic import model_validator

from amr_twin.model.config_sections import P, Section


class _Settings(Section):
    SETTINGS: ClassVar[bool] = True


class NavLimitsCfg(_Settings):
    """The twist's limits (:class:`amr_twin.navigation.kinematics.Limits`)."""

    max_v_m_s: float = P(unit="m/s", gt=0.0, le=1.5)
    min_v_m_s: float = P(unit="m/s", ge=-1.0, le=0.0)
    max_w_rad_s: float = P(unit="rad/s", gt=0.0, le=4.0)
    accel_m_s2: float = P(unit="m/s^2", gt=0.0, le=3.0)
    decel_m_s2: float = P(unit="m/s^2", gt=0.0, le=3.0)
    angular_accel_rad_s2: float = P(unit="rad/s^2", gt=0.0, le=8.0)


class NavCostmapCfg(_Settings):
    """The layered costmap (:class:`amr_twin.navigation.costmap.Costmap`) and the scan it takes."""

    inflation_radius_m: float = P(unit="m", gt=0.0, le=3.0)
    cost_scaling_per_m: float = P(unit="1/m", gt=0.0, le=30.0)
    static_tolerance_m: float = P(unit="m", ge=0.0, le=1.0)
    obstacle_range_m: float = P(unit="m", gt=0.0, le=12.0)
    raytrace_range_m: float = P(unit="m", gt=0.0, le=12.0)
    unmapped_m: float = P(unit="m", ge=0.05, le=1.0)
    unmapped_map_file_m: float = P(unit="m", ge=0.05, le=1.0)

    @model_validator(mode="after")
    def _ranges(self) -> "NavCostmapCfg":
        if self.raytrace_range_m < self.obstacle_range_m:
            raise ValueError(
                "navigation.costmap.raytrace_range_m: must be >= obstacle_range_m "
                "(what is marked must be cleared too)"
            )
        return self


class NavPlannerCfg(_Settings):
    """The global planner (:class:`amr_twin.navigation.planner.GlobalPlanner`) and when it runs."""

    planner_hz: float = P(unit="Hz", ge=0.05, le=20.0)
    off_path_m: float = P(unit="m", gt=0.0, le=5.0)
    unmapped_pad_m: float = P(unit="m", ge=0.0, le=1.0)
    people_margin_m: float = P(unit="m", ge=0.0, le=1.0)
    downsample: int = P(unit="1", ge=1, le=4)
    cost_weight: float = P(unit="1", ge=0.0, le=10.0)
    footprint_clearance_m: float = P(unit="m", ge=0.0, le=0.5)
    lead_m: float = P(unit="m", ge=0.0, le=1.5)


class NavNavigatorCfg(_Settings):
    """The navigator's cycle, goal checker and failure handling
    (:class:`amr_twin.navigation.navigator.NavParams`)."""

    controller_hz: float = P(unit="Hz", ge=5.0, le=100.0)
    xy_tolerance_m: float = P(unit="m", gt=0.0, le=2.0)
    approach_m: float = P(unit="m", gt=0.0, le=2.0)
    approach_s: float = P(unit="s", gt=0.0, le=30.0)
    yaw_tolerance_rad: float = P(unit="rad", gt=0.0, le=3.2)
    rotate_to_path_rad: float = P(unit="rad", gt=0.0, le=3.2)
    blocked_s: float = P(unit="s", gt=0.0, le=30.0)
    max_failures: int = P(unit="1", ge=0, le=50)
    progress_radius_m: float = P(unit="m", gt=0.0, le=5.0)
    progress_time_s: float = P(unit="s", gt=0.0, le=120.0)


class MppiWeightsCfg(_Settings):
    """The MPPI critics' weights (:mod:`amr_twin.navigation.mppi`)."""

    collision: float = P(unit="1", ge=0.0, le=1e6)
    obstacle: float = P(unit="1/m", ge=0.0, le=1e4)
    align: float = P(unit="1/m", ge=0.0, le=1e4)
    progress: float = P(unit="1/m", ge=0.0, le=1e4)
    goal: float = P(unit="1/m", ge=0.0, le=1e4)
    forward: float = P(unit="s/m", ge=0.0, le=1e4)
    social: float = P(unit="s^2/m^2", ge=0.0, le=1e4)
    people_collision: float = P(unit="1", ge=0.0, le=1e6)
    people: float = P(unit="1/m", ge=0.0, le=1e4)


class NavMppiCfg(_Settings):
    """The MPPI controller's samples, horizon, noise and critics
    (:class:`amr_twin.navigation.mppi.Mppi`)."""

    samples: int = P(unit="1", ge=16, le=4000)
    steps: int = P(unit="1", ge=5, le=100)
    step_s: float = P(unit="s", ge=0.02, le=0.5)
    sigma_v: float = P(unit="m/s", gt=0.0, le=2.0)
    sigma_w: float = P(unit="rad/s", gt=0.0, le=4.0)
    temperature: float = P(unit="1", gt=0.0, le=100.0)
    margin_m: float = P(unit="m", ge=0.0, le=2.0)
    social_radius_m: float = P(unit="m", gt=0.0, le=5.0)
    person_clearance_m: float = P(unit="m", ge=0.0, le=2.0)
    person_margin_m: float = P(unit="m", ge=0.0, le=3.0)
    narrow_m: float = P(unit="m", ge=0.0, le=2.0)
    narrow_v_m_s: float = P(unit="m/s", gt=0.0, le=1.5)
    weights: MppiWeightsCfg


class NavMonitorCfg(_Settings):
    """The collision monitor's zones
    (:class:`amr_twin.navigation.collision_monitor.CollisionMonitor`)."""

    pad_m: float = P(unit="m", ge=0.0, le=1.0)
    people_pad_m: float = P(unit="m", ge=0.0, le=2.0)
    time_before_collision_s: float = P(unit="s", gt=0.0, le=10.0)
    slow_pad_m: float = P(unit="m", ge=0.0, le=5.0)
    slow_ratio: float = P(unit="1", gt=0.0, le=1.0)
    people_stop_m: float = P(unit="m", ge=0.0, le=2.0)
    people_time_s: float = P(unit="s", gt=0.0, le=10.0)
    people_slow_m: float = P(unit="m", ge=0.0, le=5.0)
    people_slow_m_s: float = P(unit="m/s", gt=0.0, le=1.5)
    escape_m_s: float = P(unit="m/s", gt=0.0, le=1.0)
    escape_rad_s: float = P(unit="rad/s", gt=0.0, le=4.0)
    people_turn_m_s: float = P(unit="m/s", ge=0.0, le=0.5)
    people_stop_lag_s: float = P(unit="s", ge=0.0, le=2.0)


class NavYieldingCfg(_Settings):
    """The robot giving way to people (:class:`amr_twin.navigation.yielding.Yielding`)."""

    enabled: bool = P(unit="bool")
    margin_m: float = P(unit="m", ge=0.0, le=2.0)
    speeds_m_s: tuple[float, ...] = P(unit="m/s")
    turns_rad_s: tuple[float, ...] = P(unit="rad/s")
    step_s: float = P(unit="s", gt=0.0, le=1.0)
    standoff_m: float = P(unit="m", ge=0.0, le=3.0)
    standoff_s: float = P(unit="s", gt=0.0, le=60.0)
    back_s: float = P(unit="s", ge=0.0, le=10.0)
    pad_m: float = P(unit="m", ge=0.0, le=1.0)
    courtesy_m: float = P(unit="m", ge=0.0, le=2.0)
    courtesy_s: float = P(unit="s", ge=0.0, le=10.0)
    courtesy_forget_s: float = P(unit="s", ge=0.0, le=600.0)


class NavPeopleCfg(_Settings):
    """The people tracker (:class:`amr_twin.navigation.people.PeopleTracker`), the person's disc,
    and the robot's giving way to people (``yielding``)."""

    person_radius_m: float = P(unit="m", gt=0.0, le=1.0)
    join_m: float = P(unit="m", gt=0.0, le=1.0)
    max_size_m: float = P(unit="m", gt=0.0, le=3.0)
    range_m: float = P(unit="m", gt=0.0, le=12.0)
    gate_m: float = P(unit="m", gt=0.0, le=2.0)
    max_speed_m_s: float = P(unit="m/s", gt=0.0, le=5.0)
    alpha: float = P(unit="1", gt=0.0, le=1.0)
    beta: float = P(unit="1", gt=0.0, le=1.0)
    keep_s: float = P(unit="s", gt=0.0, le=5.0)
    confirm: int = P(unit="1", ge=1, le=10)
    min_speed_m_s: float = P(unit="m/s", ge=0.0, le=2.0)
    moved_m: float = P(unit="m", ge=0.0, le=5.0)
    horizon_s: float = P(unit="s", ge=0.0, le=10.0)
    fleet_margin_m: float = P(unit="m", ge=0.0, le=1.0)
    yielding: NavYieldingCfg


class NavMapMatchingCfg(_Settings):
    """The scan-to-map correction of the localisation
    (:class:`amr_twin.navigation.map_matching.MapMatcher`)."""

    enabled: bool = P(unit="bool")
    inlier_m: float = P(unit="m", gt=0.0, le=2.0)
    iterations: int = P(unit="1", ge=1, le=20)
    min_inliers: int = P(unit="1", ge=3, le=2000)
    max_range_m: float = P(unit="m", gt=0.0, le=12.0)
    sigma_m: float = P(unit="m", gt=0.0, le=1.0)
    step_m: float = P(unit="m", gt=0.0, le=2.0)
    step_rad: float = P(unit="rad", gt=0.0, le=1.0)
    total_m: float = P(unit="m", gt=0.0, le=5.0)
    total_rad: float = P(unit="rad", gt=0.0, le=3.2)
    feedback: bool = P(unit="bool")
    feedback_inflation: float = P(unit="1", ge=1.0, le=1e4)
    feedback_floor_m: float = P(unit="m", gt=0.0, le=5.0)
    feedback_floor_rad: float = P(unit="rad", gt=0.0, le=3.2)


class NavRecoveriesCfg(_Settings):
    """The recoveries of :mod:`amr_twin.navigation.recoveries`."""

    spin_rad: float = P(unit="rad", gt=0.0, le=6.3)
    wait_s: float = P(unit="s", gt=0.0, le=60.0)
    backup_m: float = P(unit="m", gt=0.0, le=2.0)
    backup_m_s: float = P(unit="m/s", gt=0.0, le=0.5)


class NavigationCfg(_Settings):
    """Every setting of the navigation stack (module docstring)."""

    limits: NavLimitsCfg
    costmap: NavCostmapCfg
    planner: NavPlannerCfg
    navigator: NavNavigatorCfg
    mppi: NavMppiCfg
    monitor: NavMonitorCfg
    people: NavPeopleCfg
    map_matching: NavMapMatchingCfg
    recoveries: NavRecoveriesCfg

    @model_validator(mode="after")
    def _fits(self) -> "NavigationCfg":
        if -self.limits.min_v_m_s > self.limits.max_v_m_s:
            raise ValueError(
                "navigation.limits.min_v_m_s: backing up must not be faster than max_v_m_s"
            )
        if self.recoveries.backup_m_s > -self.limits.min_v_m_s:
            raise ValueError(
                "navigation.recoveries.backup_m_s: must be <= -navigation.limits.min_v_m_s"
            )
        return self
