"""One robot on a world's loop: :class:`Robot`, a set of components on the world's hooks, clock
and bus, built from a :class:`RobotSpec`.

Its parts: the rosserial link, the plant with its battery and rolling resistance, the hall
sensors and their pending edges, the firmware, the wheel command service and client, the PC-side
nodes named in the spec (:data:`amr_twin.assembly.nodes.NODES`), the actuation, the sensors named
in the spec (:data:`amr_twin.sensors.catalog.SENSORS`), and the teleport and reset of the robot.
Each part takes the plain values it needs from the robot's configuration.

Reasons and measurements: docs/explanation/architecture.md#amr_twinassemblyrobot.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from amr_twin.assembly.nodes import NODES
from amr_twin.controllers.firmware import make_firmware
from amr_twin.controllers.wheel_command import WheelCommandClient, WheelCommandService
from amr_twin.model.config import TwinConfig
from amr_twin.ros.messages import Float64
from amr_twin.ros.ros_state import robot_static_transforms
from amr_twin.ros.rosserial import ARDUINO_TO_PC, PC_TO_ARDUINO, RosserialLink
from amr_twin.sensors.catalog import SENSORS
from amr_twin.sensors.hall import HallSensors
from amr_twin.sim.actuation import Actuation
from amr_twin.sim.component import Mount
from amr_twin.sim.observables import Observables
from amr_twin.sim.plant import Plant
from amr_twin.sim.rolling_resistance import RollingResistance

PLACED_SIGMA = 1e-4
"""Standard deviation of the pose a reset places the robot at, told to an EKF (m and rad): exact,
but for the filter's conditioning."""


@dataclass(frozen=True)
class RobotSpec:
    """One robot of a world: its parameters, where it starts, and which parts it has.

    Attributes:
        cfg: the robot's parameters (``models/amr/amr.yaml``).
        start_xy_yaw: the start pose (m, m, rad), where a reset puts it.
        physics: the robot's view of the world's physics; None: the world's own (one robot).
        world: the world's name or path (the UWB anchors it declares).
        firmware, firmware_params: the firmware by name (``FIRMWARES``) and its parameters.
        seed: the run's seed (the hall jitter, the link's losses, the sensors' noise).
        hall_jitter_us, hall_misalignment_deg: the hall sensors' timing jitter and mounting error.
        rosserial_extra_latency_us, rosserial_loss_prob: the link's added latency and losses.
        sensors: sensors by name (``SENSORS``), built in this order.
        nodes: PC-side nodes by name (``NODES``), built in this order.
        node_params: keyword arguments of a node's factory, by node name.
        faults: :class:`amr_twin.sim.faults.Fault` items injected into this robot.
    """

    cfg: TwinConfig
    start_xy_yaw: tuple[float, float, float]
    physics: object = None
    world: str = "warehouse"
    firmware: str = "faithful"
    firmware_params: object = field(default=None, compare=False)
    seed: int = 0
    hall_jitter_us: float = 0.0
    hall_misalignment_deg: float = 0.0
    rosserial_extra_latency_us: int = 0
    rosserial_loss_prob: float = 0.0
    sensors: tuple[str, ...] = ()
    nodes: tuple[str, ...] = ("odometry",)
    node_params: dict = field(default_factory=dict, compare=False)
    faults: tuple = ()


class Robot:
    """The robot of ``spec`` on ``world``'s loop (module notes): ``world`` is the
    :class:`~amr_twin.assembly.world.World` that builds it, ``bus`` the bus its parts speak on
    (the world's for a lone robot, its own in a fleet); the body here, the sensors at
    :meth:`equip`."""

    def __init__(self, world, spec: RobotSpec, bus):
        self.spec, self.world = spec, world
        self._sensor_factories = [(name, SENSORS.get(name)) for name in spec.sensors]
        node_factories = [(name, NODES.get(name)) for name in spec.nodes]
        self.physics = physics = world.physics if spec.physics is None else spec.physics
        self.clock, self.bus = world.clock, bus
        self.name = physics.prefix.rstrip("/")
        """The robot's name in the model (``amr`` alone, ``amr-2`` in a fleet)."""
        self.start_xy_yaw = tuple(float(v) for v in spec.start_xy_yaw)
        # settled at its start: how it stands after a teleport
        self._rest = physics.placement.positions()
        self.pending: list[tuple[int, int]] = []
        """SC edges ``(t_us, wheel)`` solved from the rows and not yet delivered, in time order."""
        self.bus.send_transform(robot_static_transforms(physics.model, physics.prefix), static=True)
        self._build_drive(spec)
        self._mount = Mount(
            physics,
            self.clock,
            self.bus,
            world,
            world.grid_us,
            spec.seed,
            spec.world,
            world.actors_move,
        )
        self.nodes = {
            name: factory(self._mount, spec.cfg, **spec.node_params.get(name, {}))
            for name, factory in node_factories
        }
        """The PC-side nodes built from ``spec.nodes``, by name."""
        self.rolling = RollingResistance(physics, spec.cfg)
        world.on_grid(self.rolling.update)
        world.on_grid(self.plant.battery.account)
        self.actuation = Actuation(self.plant, self.firmware, world._actuation_hooks)
        self.sensors: dict = {}
        """The sensors built from ``spec.sensors`` and by :meth:`add_sensor`, by name."""
        self.faults = None
        """The faults' injector (:class:`amr_twin.sim.fault_injector.FaultInjector`), None without
        faults."""

    def _build_drive(self, spec: RobotSpec) -> None:
        """The link, the plant, its hall sensors, the firmware and the wheel command service and
        client."""
        wheel, clock, bus = spec.cfg.wheel, self.clock, self.bus
        self.link = RosserialLink(
            clock,
            extra_latency_us=spec.rosserial_extra_latency_us,
            loss_prob=spec.rosserial_loss_prob,
            seed=spec.seed,
        )
        cfg = spec.cfg
        self.plant = Plant(
            self.physics,
            cfg.driver,
            (cfg.driver_left, cfg.driver_right),
            (cfg.motor_left, cfg.motor_right),
            cfg.battery,
        )
        self.hall = HallSensors(
            2,
            pole_pairs=wheel.hall_pole_pairs,
            misalignment_deg=spec.hall_misalignment_deg,
            jitter_us=spec.hall_jitter_us,
            seed=spec.seed,
            hysteresis_deg=wheel.hall_hysteresis_deg,
        )
        self.hall.reset(self.physics.wheel_angles_rad())
        self.firmware = make_firmware(
            spec.firmware,
            clock,
            self._arduino_publish,
            spec.firmware_params,
            edges_per_rev=wheel.sc_edges_per_rev,
        )
        self.service = WheelCommandService(bus)
        self.client = WheelCommandClient(
            bus, wheel_radius_m=wheel.radius_m, half_separation_m=wheel.separation_m / 2
        )
        if not self.firmware.connect(bus, self.link):  # else it speaks rosserial on its own UART
            bus.subscribe("wheel_Command", self._to_arduino)

    @property
    def t_s(self) -> float:
        """The world's clock time, s."""
        return self.world.t_s

    def equip(self, grid, collisions) -> None:
        """The sensors of the spec (their grid samplers after the world's) and the observables on
        the world's ``grid`` and the robot's ``collisions`` monitor."""
        self.collisions = collisions
        columns = self.physics.loop_columns
        self._columns = None if columns == slice(0, len(grid.last_row)) else columns
        """The robot's columns of the grid loop's rows; None: the whole row (a lone robot)."""
        """The robot's collision monitor (:class:`~amr_twin.sim.collisions.CollisionMonitor`)."""
        self.observables = Observables(
            self.physics, grid, self.actuation, self.plant.battery, collisions, self._columns
        )
        """What the robot shows downstream of the loop
        (:class:`~amr_twin.sim.observables.Observables`)."""
        for name, factory in self._sensor_factories:
            self.sensors[name] = factory(self._mount, self.spec.cfg)

    def inject_faults(self, hooks) -> None:
        """Schedule the spec's faults on the world's clock (``hooks``: the world's)."""
        if not self.spec.faults:
            return
        from amr_twin.sim.fault_injector import FaultInjector, FaultTargets

        world = self.world
        targets = FaultTargets(
            self.hall, self.physics, self.link, self.bus, self.actuation, lambda: world.t_phys_us
        )
        self.faults = FaultInjector(self.spec.faults, self.clock, hooks, targets)

    def start(self) -> None:
        """Start the firmware and apply its pins at time 0."""
        self.firmware.start()
        self.actuation.apply(0)

    def add_sensor(self, name: str):
        """Build the sensor ``name`` of :data:`~amr_twin.sensors.catalog.SENSORS` on the robot as
        it is now; its grid samplers run once now. Returns the sensor; ValueError (one line) for an
        unknown name or one the robot has already."""
        if name in self.sensors:
            raise ValueError(f"sensor {name!r}: the twin has it already")
        factory, samplers = SENSORS.get(name), self.world.samplers
        n = len(samplers)
        self.sensors[name] = sensor = factory(self._mount, self.spec.cfg)
        for sampler in samplers[n:]:
            sampler(self.world.t_phys_us)
        return sensor

    # -- the loop's calls ---------------------------------------------------------------
    def take_rows(self, ts: list, rows: list) -> None:
        """Solve the hall edges of a chunk from its instants ``ts`` (us) and this robot's loop
        sensor ``rows`` (:meth:`~amr_twin.sensors.hall.HallSensors.edges_from_samples`): its own
        columns of them (:attr:`~amr_twin.sim.physics.Physics.loop_columns`)."""
        columns = self._columns
        if columns is not None:
            rows = [row[columns] for row in rows]
        edges = self.hall.edges_from_samples(ts, rows)
        if edges:
            self.pending.extend(edges)

    def deliver_edges(self, t_until_us: int) -> None:
        """Deliver the pending SC edges up to ``t_until_us`` to the firmware's ISR, in time
        order."""
        pending = self.pending
        if not pending or pending[0][0] > t_until_us:
            return
        clock, isr = self.clock, self.firmware.on_sc_edge
        n = 0
        for t_e, w in pending:
            if t_e > t_until_us:
                break
            clock.run_until(max(t_e, clock.now_us))
            isr(w)
            n += 1
        del pending[:n]

    # -- rosserial bridge ---------------------------------------------------------------
    def _to_arduino(self, msg) -> None:
        self.link.send(
            PC_TO_ARDUINO,
            "wheel_Command",
            msg,
            lambda _topic, m: self.firmware.on_wheel_command(list(m.data)),
        )

    def _arduino_publish(self, topic: str, value: float) -> None:
        self.link.send(ARDUINO_TO_PC, topic, Float64(data=float(value)), self.bus.publish)

    # -- teleport and reset ----------------------------------------------------------------
    def set_pose(self, x_m: float, y_m: float, yaw_rad: float) -> None:
        """Teleport the robot to ``x_m, y_m`` heading ``yaw_rad`` (world frame) at rest
        (:meth:`~amr_twin.sim.placement.Placement.place`); ValueError (one line), the robot left
        where it was, where it would overlap the world."""
        from amr_twin.sim.start_pose import StartPoseError, check_start

        before = self.physics.placement.place(x_m, y_m, yaw_rad, self._rest)
        try:
            check_start(self.physics, f"pose {x_m:g},{y_m:g},{math.degrees(yaw_rad):g}")
        except StartPoseError as exc:
            self.physics.placement.restore(before)
            raise ValueError(str(exc).split(";")[0]) from None

    def set_payload_kg(self, mass_kg: float) -> None:
        """Carry a load of ``mass_kg`` (0: none) from the next step on: a box of ``payload.size_m``
        at ``payload.xy_m`` on the deck (:meth:`~amr_twin.sim.payload.Payload.set_kg`)."""
        from amr_twin.model.robot_spec import payload_centre_m

        cfg = self.spec.cfg
        self.physics.payload.set_kg(mass_kg, payload_centre_m(cfg), cfg.payload.size_m)

    def set_charger_a(self, current_a: float) -> None:
        """Connect a charger of ``current_a`` (0: disconnect) to the pack
        (:attr:`~amr_twin.sim.battery.Battery.charger_a`)."""
        self.plant.battery.charger_a = current_a

    def reset_state(self) -> None:
        """The robot's own state: the wheels braked (a stop through the client, so the firmware's
        loop is told as by the menu), the odometry node (if any) at the origin of ``odom``,
        standing."""
        self.client.stop()
        odometry = self.nodes.get("odometry")
        if odometry is not None:
            odometry.reset(standing=True)

    def publish_placed_pose(self, topic: str) -> None:
        """The start pose, known to within :data:`PLACED_SIGMA`, on an EKF's pose input
        ``topic`` (``map_match/pose``) in ``map``."""
        import numpy as np

        from amr_twin.ros.geometry_messages import (
            Point,
            Pose,
            PoseWithCovariance,
            PoseWithCovarianceStamped,
            Quaternion,
        )
        from amr_twin.ros.messages import Header, Time

        x, y, yaw = self.start_xy_yaw
        cov = np.zeros(36)
        cov[[0, 7, 35]] = PLACED_SIGMA**2
        self.bus.publish(
            topic,
            PoseWithCovarianceStamped(
                Header(0, Time.from_us(self.clock.now_us), "map"),
                PoseWithCovariance(
                    Pose(Point(float(x), float(y), 0.0), Quaternion.from_yaw(float(yaw))), cov
                ),
            ),
        )
