"""The PC-side nodes a robot builds by name (``TwinOptions.nodes``): the wheel odometry.

Each entry of :data:`NODES` is a :class:`~amr_twin.sim.component.ComponentFactory`: it takes
the robot's :class:`~amr_twin.sim.component.Mount`, the robot's configuration and the node's own
keyword arguments (``RobotSpec.node_params``), and builds the node from the values it needs. A
third party adds a node from its module::

    @NODES.register("speed_log")
    def speed_log(mount, cfg):
        return SpeedLog(mount.bus, mount.clock)
"""

from __future__ import annotations

from amr_twin.base.registry import Registry
from amr_twin.model.config import TwinConfig
from amr_twin.sim.component import ComponentFactory, Mount

__all__ = ["NODES"]

NODES: Registry[ComponentFactory] = Registry("nodes")
"""Node factories by name, in registration order."""


@NODES.register("odometry")
def odometry(mount: Mount, cfg: TwinConfig, calibration=None):
    """The diff-drive odometry node (:class:`~amr_twin.controllers.odometry.WheelOdometry`:
    ``odom``, ``tf``) on the nominal wheel geometry, or on ``calibration``'s
    (:class:`~amr_twin.controllers.odometry_calibration.OdometryCalibration`, a UMBmark's)."""
    from amr_twin.controllers.odometry import WheelOdometry

    wheel = cfg.wheel
    multipliers = (
        {} if calibration is None else calibration.multipliers(wheel.radius_m, wheel.separation_m)
    )
    return WheelOdometry(
        mount.bus,
        mount.clock,
        wheel_radius_m=wheel.radius_m,
        wheel_separation_m=wheel.separation_m,
        **multipliers,
    )
