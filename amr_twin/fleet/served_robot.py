"""One robot of a world served as a VDA 5050 vehicle: :class:`ServedRobot`, its navigation stack,
:class:`~amr_twin.fleet.vehicle.TwinVehicle`, :class:`~amr_twin.fleet.adapter.VehicleAdapter` and
MQTT transport with its own last will (:class:`~amr_twin.fleet.session.FleetSession` holds one
per robot).
"""

from __future__ import annotations

from functools import partial

from amr_twin.fleet.adapter import VehicleAdapter
from amr_twin.fleet.factsheet import factsheet
from amr_twin.fleet.handling import Handling, Load
from amr_twin.fleet.protocol import MANUFACTURER, Stamper
from amr_twin.fleet.vehicle import TwinVehicle
from amr_twin.analysis.se2 import yaw_of_quaternion


class ServedRobot:
    """``robot`` (:class:`~amr_twin.assembly.robot.Robot`) of a world as vehicle ``serial``: the
    navigation stack of ``nav_options`` (:func:`amr_twin.navigation.stack.attach`) on the robot's
    bus over ``static`` (the world's map), its vehicle and adapter on the world's clock; ``cfg``
    the robot's parameters (its payload carried from the start as a load), ``stations`` the
    world's charging stations, ``fleet`` the fleet sharing its poses
    (:func:`~amr_twin.navigation.stack.fleet_mates`) or None. :meth:`connect` it to a broker
    through ``pacer``."""

    def __init__(
        self, robot, cfg, static, nav_options, serial: str, map_id: str, stations, epoch, fleet=None
    ):
        from amr_twin.navigation.stack import attach

        self.robot, self.serial = robot, serial
        self.navigator = attach(robot, cfg, static, nav_options, publish=False, fleet=fleet)
        self.vehicle = TwinVehicle(robot, self.navigator, map_id, cfg.battery.charge_current_a)
        load = None
        if cfg.payload.mass_kg > 0:
            self.vehicle.set_payload_kg(cfg.payload.mass_kg)
            load = Load(cfg.payload.mass_kg)
        nav = cfg.navigation.navigator
        self.transport = None
        self.adapter = VehicleAdapter(
            self.vehicle,
            robot.clock,
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

    def connect(self, url: str, interface: str, pacer) -> None:
        """Connect to the broker at ``url`` (its last will: CONNECTIONBROKEN), say ONLINE and send
        the factsheet; messages received act through ``pacer`` (the world's thread)."""
        from amr_twin.fleet.transport import MqttTransport

        def received(subtopic: str, payload: bytes) -> None:
            pacer.post(partial(self.adapter.handle, subtopic, payload))

        transport = MqttTransport(
            url,
            interface,
            self.serial,
            received,
            self.adapter.connection("CONNECTIONBROKEN"),
            MANUFACTURER,
        )
        transport.connect()
        self.transport = transport
        transport.publish("connection", self.adapter.connection("ONLINE"))
        self.adapter.publish_factsheet()

    def _send(self, subtopic: str, msg: dict) -> None:
        if self.transport is not None:
            self.transport.publish(subtopic, msg)

    def true_pose(self) -> tuple[float, float, float]:
        """The robot's true pose now (x_m, y_m, yaw_rad), from the physics."""
        row = self.robot.observables.loop_sensors()
        w, x, y, z = row[7:11]
        return (
            float(row[4]),
            float(row[5]),
            yaw_of_quaternion(w, x, y, z),
        )

    def summary(self) -> dict:
        """The vehicle's part of a run's summary: its serial, the messages sent by topic and
        received, the last state, the true pose (m, rad)."""
        counts: dict[str, int] = {}
        for _t, sub, _m in self.adapter.log:
            counts[sub] = counts.get(sub, 0) + 1
        states = [m for _t, sub, m in self.adapter.log if sub == "state"]
        x, y, yaw = self.true_pose()
        return {
            "serialNumber": self.serial,
            "messages_sent": counts,
            "messages_received": self.transport.messages_in if self.transport else 0,
            "true_pose": {"x_m": x, "y_m": y, "yaw_rad": yaw},
            "last_state": states[-1] if states else None,
        }

    def close(self) -> None:
        """Stop the adapter, say OFFLINE and disconnect."""
        self.adapter.close()
        if self.transport is not None:
            self.transport.close(self.adapter.connection("OFFLINE"))
            self.transport = None
