"""The navigation's plug-ins by name: local controllers, planners, localisation sources, recoveries.

Each registry holds factories (:mod:`amr_twin.navigation.interfaces` says what they build); the
stack builds from them by name and the command line takes its choices, help and checks from them.
The built-ins are declared here and import their modules at first use (as nav2's pluginlib loads
a plug-in's library), so that listing them imports no numpy. A third party registers its own from
its module, e.g. ``CONTROLLERS.register("straight", factory)``.
"""

from __future__ import annotations

from collections.abc import Callable

from amr_twin.base.registry import Registry
from amr_twin.navigation.interfaces import (
    LocalController,
    LocalisationSource,
    Planner,
    RecoveryBehaviour,
)

__all__ = ["CONTROLLERS", "LOCALISATIONS", "PLANNERS", "RECOVERIES", "ROUND_ROBIN", "help_text"]

CONTROLLERS: Registry[Callable[..., LocalController]] = Registry("--controller")
"""Local controllers: ``factory(costmap, footprint, nav, seed) -> LocalController`` (``nav``: the
parameter file's ``navigation`` section)."""
PLANNERS: Registry[Callable[..., Planner]] = Registry("planner")
"""Global planners: ``factory(costmap, footprint, nav) -> Planner``."""
LOCALISATIONS: Registry[Callable[[], LocalisationSource]] = Registry("--localisation")
"""Localisation sources: ``factory() -> LocalisationSource`` (a class that subclasses it)."""
RECOVERIES: Registry[Callable[..., RecoveryBehaviour]] = Registry("recovery")
"""Recoveries: ``factory(costmap, footprint, limits, dt_s, **settings) -> RecoveryBehaviour``."""
ROUND_ROBIN = ("clear_costmaps", "spin", "wait", "backup")
"""nav2's default recovery order, one per failure."""


def help_text(registry: Registry) -> str:
    """The names with the first line of each factory's docstring: ``a (what a is) or b (...)``."""
    said = [
        f"{name} ({(registry.get(name).__doc__ or '').strip().splitlines()[0].rstrip('.')})"
        if registry.get(name).__doc__
        else name
        for name in registry
    ]
    return said[0] if len(said) == 1 else ", ".join(said[:-1]) + " or " + said[-1]


@CONTROLLERS.register("mppi")
def _mppi(costmap, footprint, nav, seed: int = 0):
    """sampling MPC with nav2's MPPI critics, people included"""
    from amr_twin.navigation.kinematics import Limits
    from amr_twin.navigation.mppi import Mppi

    m = nav.mppi.model_dump()
    limits, dt_s = Limits(**nav.limits.model_dump()), 1.0 / nav.navigator.controller_hz
    return Mppi(
        costmap,
        footprint,
        limits,
        dt_s,
        **{k: v for k, v in m.items() if k != "weights"},
        weights=m["weights"],
        person_radius_m=nav.people.person_radius_m,
        prediction_s=nav.people.horizon_s,
        seed=seed,
    )


@CONTROLLERS.register("rpp")
def _rpp(costmap, footprint, nav, seed: int = 0):
    """regulated pure pursuit"""
    from amr_twin.navigation.kinematics import Limits
    from amr_twin.navigation.rpp import RegulatedPurePursuit

    return RegulatedPurePursuit(
        costmap, footprint, Limits(**nav.limits.model_dump()), 1.0 / nav.navigator.controller_hz
    )


@PLANNERS.register("grid")
def _grid(costmap, footprint, nav):
    """Dijkstra on the costmap's grid, the path shortened

    Room to turn the footprint kept; people standing in the way kept the monitor's ``people_stop_m``
    and ``people_margin_m`` more from the robot's sides."""
    from amr_twin.navigation.planner import GlobalPlanner

    p = nav.planner
    r_in = footprint.inscribed_radius_m
    people_m = nav.people.person_radius_m + nav.monitor.people_stop_m + r_in + p.people_margin_m
    return GlobalPlanner(
        costmap,
        downsample=p.downsample,
        cost_weight=p.cost_weight,
        turn_room_m=footprint.circumscribed_radius_m,
        unmapped_pad_m=p.unmapped_pad_m,
        people_m=people_m,
        footprint=footprint,
        footprint_clearance_m=p.footprint_clearance_m,
        lead_m=p.lead_m,
    )


@LOCALISATIONS.register("truth")
class GroundTruthSource(LocalisationSource):
    """the twin's ground truth

    A perfect localiser (as Gazebo's p3d plug-in): isolates the planner and the controller."""

    topic, exact = "ground_truth/odom", True

    def attach(self, twin, cfg) -> None:
        """The twin's true pose on :attr:`topic` (sensors/ground_truth.py)."""
        from amr_twin.sensors.ground_truth import GroundTruth

        twin.ground_truth = GroundTruth(twin.physics, twin.clock, twin.bus)


@LOCALISATIONS.register("ekf")
class EkfSource(LocalisationSource):
    """odometry + gyro + UWB, held to the map

    The EKF of amr_twin/estimation/ekf.py in ``map``; it takes the scan-to-map match in."""

    topic, takes_matches = "odometry/filtered", True

    def attach(self, twin, cfg) -> None:
        """The EKF on the bus, with the twin's UWB tag (added if the twin has none)."""
        from amr_twin.estimation.ekf import EkfNode

        uwb = (twin.sensors.get("uwb") or twin.add_sensor("uwb")).cfg  # ranges to the anchors
        twin.ekf = EkfNode(
            cfg.ekf,
            wheel_separation_m=cfg.wheel.separation_m,
            use_imu=True,
            use_uwb=True,
            uwb=uwb,
            initial_pose=twin.start_xy_yaw,
            bus=twin.bus,
        )


@LOCALISATIONS.register("odom")
class WheelOdometrySource(LocalisationSource):
    """wheel odometry alone

    In ``odom``, which starts at the start pose; the diff-drive node publishes it."""

    topic, in_map = "odom", False


@RECOVERIES.register("clear_costmaps")
def _clear_costmaps(costmap, footprint, limits, dt_s: float, **settings):
    """nav2's ClearEntireCostmap: the obstacle layer forgotten"""
    from amr_twin.navigation.recoveries import ClearCostmaps

    return ClearCostmaps(costmap, footprint, limits, dt_s, **settings)


@RECOVERIES.register("spin")
def _spin(costmap, footprint, limits, dt_s: float, **settings):
    """nav2's Spin: a turn in place (``angle_rad``)"""
    from amr_twin.navigation.recoveries import Spin

    return Spin(costmap, footprint, limits, dt_s, **settings)


@RECOVERIES.register("wait")
def _wait(costmap, footprint, limits, dt_s: float, **settings):
    """nav2's Wait: standing still (``duration_s``)"""
    from amr_twin.navigation.recoveries import Wait

    return Wait(costmap, footprint, limits, dt_s, **settings)


@RECOVERIES.register("backup")
def _backup(costmap, footprint, limits, dt_s: float, **settings):
    """nav2's BackUp: reversing (``distance_m``, ``speed_m_s``)"""
    from amr_twin.navigation.recoveries import BackUp

    return BackUp(costmap, footprint, limits, dt_s, **settings)
