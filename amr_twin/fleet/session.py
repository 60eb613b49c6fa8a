"""One twin as a VDA 5050 vehicle on an MQTT broker: the twin with its navigation stack, the
adapter, the transport, the embedded broker when no broker is given, paced in real time (``amr-twin
fleet``).

Messages from the broker arrive in paho's thread and are handed to the twin's thread through the
:class:`~amr_twin.live.pacer.Pacer` (they act at its next tick, 20 ms of simulated time); the
adapter's messages go out from the twin's thread as they are made.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import partial
from pathlib import Path

from amr_twin.fleet.adapter import VehicleAdapter
from amr_twin.fleet.factsheet import factsheet
from amr_twin.fleet.handling import Handling, Load
from amr_twin.fleet.protocol import INTERFACE, MANUFACTURER, Stamper, check_name
from amr_twin.fleet.vehicle import TwinVehicle


@dataclass(frozen=True)
class FleetOptions:
    """The run: ``world``, the robot's start (x_m, y_m, yaw_rad; None: the world's), the broker
    (None: an embedded one), the interface name, ``rate`` (simulated seconds per wall second, 0: as
    fast as possible)."""

    world: str = "aisles"
    start_xy_yaw: tuple | None = None
    url: str | None = None
    interface: str = INTERFACE
    rate: float = 1.0
    seed: int = 0
    localisation: str = "ekf"
    controller: str = "mppi"
    firmware: str = "improved"


def map_id(world: str) -> str:
    """The VDA 5050 mapId of a world: its name (a file's stem)."""
    return Path(world).stem if any(c in str(world) for c in "/.") else str(world)


class FleetSession:
    """The twin of ``cfg`` as vehicle ``serial`` (module docstring); :meth:`run`, then
    :meth:`close`. Built without its payload, which the physics carries from the start as a load
    (:meth:`~amr_twin.assembly.twin.Twin.set_payload_kg`) so that a drop can take it off."""

    def __init__(self, cfg, options: FleetOptions, serial: str = "amr-1", epoch=None):
        from amr_twin.fleet.broker import EmbeddedBroker
        from amr_twin.fleet.transport import MqttTransport, broker_address
        from amr_twin.live.pacer import Pacer
        from amr_twin.navigation.stack import NavigationOptions, attach, load_static_map
        from amr_twin.assembly.twin import Twin, TwinOptions
        from amr_twin.model.config import with_values
        from amr_twin.model.worlds import charging_stations

        check_name("--interface", options.interface)
        if options.url is not None:
            broker_address(options.url)
        self.options, self.serial = options, serial
        stations = charging_stations(options.world)
        self.twin = Twin(
            with_values(cfg, {"payload.mass_kg": 0.0}),
            TwinOptions(
                firmware=options.firmware,
                world=options.world,
                seed=options.seed,
                start_xy_yaw=options.start_xy_yaw,
                sensors=("imu", "lidar"),
                visuals=False,
            ),
        )
        static = load_static_map(cfg, options.world, None)
        self.navigator = attach(
            self.twin,
            cfg,
            static,
            NavigationOptions(
                goals=(),
                localisation=options.localisation,
                controller=options.controller,
                seed=options.seed,
            ),
            publish=False,
        )
        self.vehicle = TwinVehicle(
            self.twin, self.navigator, map_id(options.world), cfg.battery.charge_current_a
        )
        load = None
        if cfg.payload.mass_kg > 0:
            self.vehicle.set_payload_kg(cfg.payload.mass_kg)
            load = Load(cfg.payload.mass_kg)
        nav = cfg.navigation.navigator
        self.transport = None
        self.adapter = VehicleAdapter(
            self.vehicle,
            self.twin.clock,
            self._send,
            Stamper(serial, epoch, MANUFACTURER),
            factsheet(cfg),
            xy_tolerance_m=nav.xy_tolerance_m,
            handling=Handling(
                self.vehicle,
                cfg.payload.max_mass_kg,
                cfg.payload.handling_time_s,
                stations,
                nav.xy_tolerance_m,
                nav.yaw_tolerance_rad,
                load,
            ),
        )
        self.pacer = Pacer(self.twin, options.rate)
        self.broker = EmbeddedBroker().start() if options.url is None else None
        url = options.url if options.url is not None else self.broker.url
        try:
            transport = MqttTransport(
                url,
                options.interface,
                serial,
                self._received,
                self.adapter.connection("CONNECTIONBROKEN"),
                MANUFACTURER,
            )
            transport.connect()
        except OSError:
            self._stop_broker()
            raise
        self.transport = transport
        self.url = url
        transport.publish("connection", self.adapter.connection("ONLINE"))
        self.adapter.publish_factsheet()

    def _send(self, subtopic: str, msg: dict) -> None:
        if self.transport is not None:
            self.transport.publish(subtopic, msg)

    def _received(self, subtopic: str, payload: bytes) -> None:
        self.pacer.post(partial(self.adapter.handle, subtopic, payload))

    def run(self, duration_s: float) -> None:
        """Run the twin ``duration_s`` simulated seconds, paced to the rate."""
        self.twin.advance(duration_s)

    def true_pose(self) -> tuple[float, float, float]:
        """The robot's true pose now (x_m, y_m, yaw_rad), from the physics."""
        row = self.twin.observables.loop_sensors()
        w, x, y, z = row[7:11]
        return (
            float(row[4]),
            float(row[5]),
            math.atan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z)),
        )

    def summary(self) -> dict:
        """What the run did: the vehicle, the broker, the messages sent by topic, the last state,
        the true pose."""
        counts: dict[str, int] = {}
        for _t, sub, _m in self.adapter.log:
            counts[sub] = counts.get(sub, 0) + 1
        states = [m for _t, sub, m in self.adapter.log if sub == "state"]
        x, y, yaw = self.true_pose()
        return {
            "serialNumber": self.serial,
            "manufacturer": MANUFACTURER,
            "interfaceName": self.options.interface,
            "broker": self.url,
            "embedded_broker": self.broker is not None,
            "sim_s": self.twin.t_s,
            "messages_sent": counts,
            "messages_received": self.transport.messages_in if self.transport else 0,
            "true_pose": {"x_m": x, "y_m": y, "yaw_rad": yaw},
            "last_state": states[-1] if states else None,
        }

    def close(self) -> None:
        """Say OFFLINE, disconnect, stop the pacer and the embedded broker."""
        self.pacer.close()
        self.adapter.close()
        if self.transport is not None:
            self.transport.close(self.adapter.connection("OFFLINE"))
            self.transport = None
        self._stop_broker()

    def _stop_broker(self) -> None:
        if self.broker is not None:
            self.broker.stop()
            self.broker = None
