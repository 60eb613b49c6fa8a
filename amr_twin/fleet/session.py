"""A world of robots as VDA 5050 vehicles on an MQTT broker: the world (one robot: the
:class:`~amr_twin.assembly.twin.Twin`; several: :func:`~amr_twin.assembly.fleet_world.fleet_world`),
each robot served with its navigation stack, adapter and transport
(:class:`~amr_twin.fleet.served_robot.ServedRobot`), the embedded broker when no broker is given,
paced in real time (``amr-twin fleet``).

Messages from the broker arrive in paho's thread and are handed to the world's thread through the
:class:`~amr_twin.live.pacer.Pacer` (they act at its next tick, 20 ms of simulated time); the
adapters' messages go out from the world's thread as they are made.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

from amr_twin.fleet.protocol import INTERFACE, MANUFACTURER, check_name
from amr_twin.fleet.served_robot import ServedRobot

DISTANCE_EVERY_US = 100_000
"""How often a fleet's least distance between robots is sampled, us of simulated time."""


@dataclass(frozen=True)
class FleetOptions:
    """The run: ``world``, the robots' starts (one (x_m, y_m, yaw_rad) a robot; a lone robot's may
    be None: the world's), the broker (None: an embedded one), the interface name, ``rate``
    (simulated seconds per wall second, 0: as fast as possible); ``shared_poses``: several robots
    share their pose estimates (:func:`~amr_twin.navigation.stack.fleet_mates`), so each keeps
    the others as obstacles but does not take them for people to give way to; ``visuals``: a lone
    robot's visual geoms (for a recording or a live view; a fleet's world always has them)."""

    world: str = "aisles"
    starts: tuple = (None,)
    url: str | None = None
    interface: str = INTERFACE
    rate: float = 1.0
    seed: int = 0
    localisation: str = "ekf"
    controller: str = "mppi"
    firmware: str = "improved"
    shared_poses: bool = True
    visuals: bool = False


def map_id(world: str) -> str:
    """The VDA 5050 mapId of a world: its name (a file's stem)."""
    return Path(world).stem if any(c in str(world) for c in "/.") else str(world)


class FleetSession:
    """The robots of ``cfg`` at ``options.starts`` as vehicles ``serials`` (default amr-1 ...
    amr-N; module docstring); :meth:`run`, then :meth:`close`. Built without their payload, which
    the physics carries from the start as a load so that a drop can take it off. Robot ``i``
    (0-based) navigates with seed ``options.seed + i``."""

    def __init__(self, cfg, options: FleetOptions, serials=None, epoch=None):
        from amr_twin.assembly.twin import Twin, TwinOptions
        from amr_twin.fleet.broker import EmbeddedBroker
        from amr_twin.fleet.transport import broker_address
        from amr_twin.live.pacer import Pacer
        from amr_twin.model.config import with_values
        from amr_twin.model.worlds import charging_stations
        from amr_twin.navigation.stack import NavigationOptions, fleet_mates, load_static_map

        check_name("--interface", options.interface)
        if options.url is not None:
            broker_address(options.url)
        n = len(options.starts)
        serials = tuple(f"amr-{i}" for i in range(1, n + 1)) if serials is None else serials
        if len(serials) != n:
            raise ValueError(f"serials: {len(serials)} for {n} robots; one a robot")
        self.options, self.serials = options, tuple(serials)
        stations = charging_stations(options.world)
        twin_options = TwinOptions(
            firmware=options.firmware,
            world=options.world,
            seed=options.seed,
            start_xy_yaw=options.starts[0],
            sensors=("imu", "lidar"),
            visuals=options.visuals,
        )
        bare = with_values(cfg, {"payload.mass_kg": 0.0})
        if n == 1:
            self.world = Twin(bare, twin_options)
        else:
            from amr_twin.assembly.fleet_world import fleet_world

            self.world = fleet_world(bare, twin_options, options.starts)
        """The world (a :class:`~amr_twin.assembly.twin.Twin` for one robot)."""
        static = load_static_map(cfg, options.world, None)
        fleet = fleet_mates(cfg) if options.shared_poses and n > 1 else None
        self.vehicles = [
            ServedRobot(
                robot,
                cfg,
                static,
                NavigationOptions(
                    goals=(),
                    localisation=options.localisation,
                    controller=options.controller,
                    seed=options.seed + i,
                ),
                serial,
                map_id(options.world),
                stations,
                epoch,
                fleet,
            )
            for i, (robot, serial) in enumerate(zip(self.world.robots, self.serials))
        ]
        """One :class:`~amr_twin.fleet.served_robot.ServedRobot` a robot, in order."""
        self.least_distance_m = math.inf
        """The least distance between two robots' centres so far (sampled every 0.1 s), m; inf
        for one robot."""
        if n > 1:
            self.world.clock.schedule_every(
                DISTANCE_EVERY_US, DISTANCE_EVERY_US, self._sample_distance
            )
        self.pacer = Pacer(self.world, options.rate)
        self.broker = EmbeddedBroker().start() if options.url is None else None
        self.url = options.url if options.url is not None else self.broker.url
        try:
            for served in self.vehicles:
                served.connect(self.url, options.interface, self.pacer)
        except OSError:
            for served in self.vehicles:
                served.close()
            self._stop_broker()
            raise

    def _sample_distance(self) -> None:
        poses = [served.true_pose() for served in self.vehicles]
        for i, (x1, y1, _) in enumerate(poses):
            for x2, y2, _ in poses[i + 1 :]:
                self.least_distance_m = min(self.least_distance_m, math.hypot(x1 - x2, y1 - y2))

    def run(self, duration_s: float) -> None:
        """Run the world ``duration_s`` simulated seconds, paced to the rate."""
        self.world.advance(duration_s)

    def summary(self) -> dict:
        """What the run did: the broker, the simulated time; one robot: its vehicle's summary
        (:meth:`~amr_twin.fleet.served_robot.ServedRobot.summary`) at the top level; several:
        ``vehicles`` (one each), ``collisions`` (every robot's, tagged) and the least distance
        between two robots' centres (m)."""
        out = {
            "manufacturer": MANUFACTURER,
            "interfaceName": self.options.interface,
            "broker": self.url,
            "embedded_broker": self.broker is not None,
            "sim_s": self.world.t_s,
        }
        if len(self.vehicles) == 1:
            vehicle = self.vehicles[0].summary()
            return {"serialNumber": vehicle.pop("serialNumber"), **out, **vehicle}
        return {
            **out,
            "vehicles": [served.summary() for served in self.vehicles],
            "collisions": self.world.collision_records(),
            "least_distance_m": self.least_distance_m,
        }

    def close(self) -> None:
        """Say OFFLINE, disconnect, stop the pacer and the embedded broker."""
        self.pacer.close()
        for served in self.vehicles:
            served.close()
        self._stop_broker()

    def _stop_broker(self) -> None:
        if self.broker is not None:
            self.broker.stop()
            self.broker = None
