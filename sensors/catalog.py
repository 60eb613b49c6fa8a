"""The sensors a twin builds by name (``TwinOptions.sensors``): the IMU, the LiDAR, the UWB tag.

Each entry of :data:`SENSORS` is a :class:`~amr_twin.sim.component.ComponentFactory`: it takes
the loop's :class:`~amr_twin.sim.component.Mount` and the run's configuration, and builds its
sensor from its own section (``imu:``, ``lidar:``, ``uwb:`` of ``models/amr/amr.yaml``) and a
seed of its own. A third party adds a sensor from its module::

    @SENSORS.register("wheel_angle")
    def wheel_angle(mount, cfg):
        return WheelAngleSensor(mount.physics, mount.clock, mount.bus, period_us=20_000)
"""

from __future__ import annotations

from amr_twin.base.registry import Registry
from amr_twin.model.config import TwinConfig
from amr_twin.sim.component import ComponentFactory, Mount

__all__ = ["SENSORS"]

SENSORS: Registry[ComponentFactory] = Registry("--sensors")
"""Sensor factories by name, in registration order."""

ACTOR_CAST_US = 20_000
"""With actors moving, the LiDAR casts every 20 ms (each beam sees them within ~2 cm of where
they were at its instant) rather than once a rotation (up to 0.27 m off for a walker), us."""


@SENSORS.register("imu")
def imu(mount: Mount, cfg: TwinConfig):
    """The Adafruit 9-DOF (:class:`~amr_twin.sensors.imu.ImuSensor`) sampled on the loop's grid;
    seed ``[seed, 1]``."""
    from amr_twin.sensors.imu import ImuSensor

    sensor = ImuSensor(
        mount.physics, mount.clock, mount.bus, cfg.imu, seed=[mount.seed, 1], autostart=False
    )
    sensor.start(grid_us=mount.grid_us, samplers=mount.samplers)
    return sensor


@SENSORS.register("lidar")
def lidar(mount: Mount, cfg: TwinConfig):
    """The RPLIDAR A1 (:class:`~amr_twin.sensors.lidar.Lidar`) cast on the loop's grid;
    seed ``[seed, 2]``."""
    from amr_twin.sensors.lidar import Lidar

    cast = {"loop_cast_us": ACTOR_CAST_US} if mount.actors else {}
    sensor = Lidar(
        mount.physics,
        mount.clock,
        mount.bus,
        cfg.lidar,
        seed=[mount.seed, 2],
        autostart=False,
        **cast,
    )
    sensor.start_motor(grid_us=mount.grid_us, samplers=mount.samplers)
    return sensor


@SENSORS.register("uwb")
def uwb(mount: Mount, cfg: TwinConfig):
    """The DWM1000 tag (:class:`~amr_twin.sensors.uwb.UwbSensor`) ranging to the anchors the
    world declares (:func:`~amr_twin.model.worlds.uwb_anchors_xy_m`), else to ``uwb.anchors_*``;
    seed ``[seed, 3]``."""
    from amr_twin.model.worlds import uwb_anchors_xy_m
    from amr_twin.sensors.uwb import UwbSensor

    site, anchors = cfg.uwb, uwb_anchors_xy_m(mount.world)
    if anchors is not None:
        site = site.model_copy(
            update={"anchors_x_m": tuple(anchors[:, 0]), "anchors_y_m": tuple(anchors[:, 1])}
        )
    return UwbSensor(mount.physics, mount.clock, mount.bus, site, seed=[mount.seed, 3])
