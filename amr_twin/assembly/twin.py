"""The twin assembled: the simulation loop with its physics, plant, hall sensors, firmware and
PC-side nodes on one clock.

Reasons and measurements: docs/explanation/architecture.md#amr_twinassemblytwin."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from amr_twin.ros.bus import Bus
from amr_twin.sim.actuation import Actuation
from amr_twin.base.clock import VirtualClock
from amr_twin.sim.collisions import CollisionMonitor
from amr_twin.sim.component import Mount
from amr_twin.sim.grid_loop import GridLoop
from amr_twin.sim.hooks import Hooks
from amr_twin.sim.observables import Observables
from amr_twin.model.config import TwinConfig
from amr_twin.model.tyre_stability import announce, tyre_timestep
from amr_twin.controllers.firmware import make_firmware
from amr_twin.controllers.odometry import WheelOdometry
from amr_twin.controllers.wheel_command import WheelCommandClient, WheelCommandService
from amr_twin.ros.messages import Float64
from amr_twin.sim.settled_physics import settled_physics
from amr_twin.sim.plant import Plant
from amr_twin.sim.rolling_resistance import RollingResistance
from amr_twin.ros.ros_state import robot_static_transforms
from amr_twin.ros.rosserial import ARDUINO_TO_PC, PC_TO_ARDUINO, RosserialLink
from amr_twin.sensors.hall import HallSensors

US = 1_000_000


@dataclass(frozen=True)
class TwinOptions:
    """Run options that are not physical parameters."""

    firmware: str = "faithful"
    world: str = "warehouse"
    seed: int = 0
    start_xy_yaw: tuple[float, float, float] | None = (
        0.0,
        0.0,
        0.0,
    )  # x_m, y_m, yaw_rad; None: the world's
    # own start (amr_twin.model.worlds.default_start: the warehouse's is the west end of its central
    # aisle; the CLI's default)
    settle_s: float = 0.5
    record_every_steps: int = (
        10  # time series at 100 Hz with 1 ms steps (steps of sim.timestep_s: twice as
    )
    # many physics steps when the tyres' guard halved it, amr_twin.model.tyre_stability)
    hall_jitter_us: float = 0.0
    hall_misalignment_deg: float = 0.0
    rosserial_extra_latency_us: int = 0
    rosserial_loss_prob: float = 0.0
    check_every_s: float = 0.5  # divergence check period
    sensors: tuple[
        str, ...
    ] = ()  # sensors by name (amr_twin.sensors.catalog.SENSORS): "imu" (imu/data_raw,
    # imu/mag), "lidar" (scan), "uwb" (uwb/range); () none
    stop_on_collision: bool = (
        False  # halt the twin at the first collision (amr_twin.sim.collisions)
    )
    odometry: bool = (
        True  # the wheel odometry node (odom, tf); off for runs nothing reads it from (a sweep
    )
    # point): it only publishes, so the drive is the same to the bit without it
    faults: tuple = ()  # amr_twin.sim.faults.Fault items, injected at their times
    # amr_twin.model.worlds.Obstacle boxes added to the world (unmapped: no map holds them)
    obstacles: tuple = ()
    visuals: bool = (
        True  # the robot's visual geoms in the model; off for runs nothing draws (no .rrd, no live
    )
    # view): they collide with nothing and weigh nothing, so the dynamics are the same to the bit,
    # ~15 % cheaper
    # amr_twin.model.actors.Actor items: people and pallet jacks moved on the grid
    actors: tuple = ()
    # (amr_twin.sim.actors), their true poses on actors/poses
    firmware_params: object = field(default=None, compare=False)
    odometry_calibration: object = (
        None  # controllers/odometry_calibration.OdometryCalibration: the odometry
    )
    # node's effective wheel radii and wheelbase (a UMBmark calibration); None: the nominal geometry

    def __post_init__(self) -> None:
        if type(self.sensors) is not tuple or not all(type(name) is str for name in self.sensors):
            raise ValueError(
                f"sensors: {self.sensors!r} must be a tuple of sensor names, e.g. ('imu', 'lidar')"
            )


PLACED_SIGMA = 1e-4
"""Standard deviation of the pose a reset places the robot at, told to an EKF (m and rad): exact,
but for the filter's conditioning."""


class Twin(Hooks):
    """The whole robot: build it, then :meth:`advance` it in simulated time.

    Code downstream of the loop subscribes to its hooks (:class:`~amr_twin.sim.hooks.Hooks`:
    ``on_grid``, ``on_grid_rows``, ``on_event``, ``on_actuation``, ``on_message``) and reads
    :attr:`observables`; it does not reach into :attr:`physics`, :attr:`plant`, :attr:`hall`
    or :attr:`firmware` (tests/sim/test_hooks.py). The sensors named in ``options.sensors`` are
    built from :data:`amr_twin.sensors.catalog.SENSORS` (:mod:`amr_twin.sim.component`):
    :attr:`sensors`."""

    def __init__(self, cfg: TwinConfig, options: TwinOptions = TwinOptions()):
        from amr_twin.sensors.catalog import SENSORS

        factories = [
            (name, SENSORS.get(name)) for name in options.sensors
        ]  # an unknown name: before any work
        self.cfg, self.options = cfg, options
        self._build_physics(cfg, options)
        self.clock = VirtualClock()
        self.bus = Bus(self.clock)
        self._init_hooks(self.bus)
        self.bus.send_transform(
            robot_static_transforms(self.physics.model), static=True
        )  # laser, imu_link, uwb_tag
        self._build_drive(cfg, options)
        self._build_loop(cfg, options)
        self._mount = Mount(
            self.physics,
            self.clock,
            self.bus,
            self,
            self.grid_us,
            options.seed,
            options.world,
            bool(options.actors),
        )
        self.sensors = {name: factory(self._mount, cfg) for name, factory in factories}
        """The sensors built from ``options.sensors`` and by :meth:`add_sensor`, by name, in that
        order."""
        self._pending: list[tuple[int, int]] = []  # SC edges (t_us, wheel) not yet delivered
        self._next_check_us = int(options.check_every_s * US)
        for sampler in self.samplers:
            sampler(0)
        self.faults = None
        if options.faults:
            from amr_twin.sim.fault_injector import FaultInjector, FaultTargets

            self.faults = FaultInjector(
                options.faults,
                self.clock,
                self,
                FaultTargets(
                    self.hall,
                    self.physics,
                    self.link,
                    self.bus,
                    self.actuation,
                    lambda: self.t_phys_us,
                ),
            )
        self.firmware.start()
        self.actuation.apply(0)

    def _build_physics(self, cfg: TwinConfig, options: TwinOptions) -> None:
        """The robot in its world at its start pose, settled; the floor's friction field; the
        timestep."""
        from amr_twin.model.worlds import default_start

        start = (
            options.start_xy_yaw
            if options.start_xy_yaw is not None
            else default_start(options.world)
        )
        self.start_xy_yaw = tuple(float(v) for v in start)
        pose = f"{start[0]:g},{start[1]:g},{math.degrees(start[2]):g}"
        where = (
            f"--start {pose} in world {options.world}"
            if options.start_xy_yaw is not None
            else f"the start pose {pose} of world {options.world}"
        )
        physics, urdf = settled_physics(
            cfg,
            options.world,
            self.start_xy_yaw,
            options.visuals,
            "imu" in options.sensors,
            options.settle_s,
            where,
            tuple(options.actors),
            options.obstacles,
        )
        self.physics = physics
        self._rest = (
            physics.positions()
        )  # the robot settled at its start: how it stands after a teleport
        self.floor = None
        """The floor's friction field of this run (:mod:`amr_twin.sim.floor_friction`), drawn from
        the seed with ``sim.floor_friction_field`` and the brush tyres; None otherwise."""
        if cfg.sim.floor_friction_field and physics.tyres_engine is not None:
            from amr_twin.sim.floor_friction import draw

            self.floor = draw(cfg, options.seed)
            physics.set_floor_friction(self.floor)
        self.urdf = urdf
        """The robot description as built (``/robot_description`` of a recording)."""
        self.tyre_timestep = tyre_timestep(cfg)
        """The brush tyres' guard (:mod:`amr_twin.model.tyre_stability`): the timestep the model was
        built with, halved from ``sim.timestep_s`` when the tyres' explicit states needed it (said
        on stderr)."""
        announce(self.tyre_timestep)
        self.dt_us = int(round(self.physics.timestep_s * US))
        self.t_phys_us = 0

    def _build_drive(self, cfg: TwinConfig, options: TwinOptions) -> None:
        """The plant, its hall sensors, the firmware behind its rosserial link and the PC side: the
        wheel command service and client, the odometry node."""
        self.link = RosserialLink(
            self.clock,
            extra_latency_us=options.rosserial_extra_latency_us,
            loss_prob=options.rosserial_loss_prob,
            seed=options.seed,
        )
        self.plant = Plant(cfg, self.physics)
        wheel = cfg.wheel
        self.hall = HallSensors(
            2,
            pole_pairs=wheel.hall_pole_pairs,
            misalignment_deg=options.hall_misalignment_deg,
            jitter_us=options.hall_jitter_us,
            seed=options.seed,
            hysteresis_deg=wheel.hall_hysteresis_deg,
        )
        self.hall.reset(self.physics.wheel_angles_rad())
        self.firmware = make_firmware(
            options.firmware,
            self.clock,
            self._arduino_publish,
            options.firmware_params,
            edges_per_rev=wheel.sc_edges_per_rev,
        )
        self.service = WheelCommandService(self.bus)
        self.client = WheelCommandClient(
            self.bus, wheel_radius_m=wheel.radius_m, half_separation_m=wheel.separation_m / 2
        )
        if not self.firmware.connect(
            self.bus, self.link
        ):  # else it speaks rosserial on its own UART
            self.bus.subscribe("wheel_Command", self._to_arduino)
        calibration = options.odometry_calibration
        self.odometry = (
            WheelOdometry(
                self.bus,
                self.clock,
                wheel_radius_m=wheel.radius_m,
                wheel_separation_m=wheel.separation_m,
                **(
                    {}
                    if calibration is None
                    else calibration.multipliers(wheel.radius_m, wheel.separation_m)
                ),
            )
            if options.odometry
            else None
        )

    def _build_loop(self, cfg: TwinConfig, options: TwinOptions) -> None:
        """The record grid and the loop's own grid samplers, in the order they run: the rolling
        resistance from the present loads, the battery's accounting, the actors, the collision
        monitor (the sensors' come after them: the ``on_grid`` hook, amr_twin/sim/hooks.py); the
        actuation and the observables."""
        self.grid_every = (
            max(1, int(options.record_every_steps)) * self.tyre_timestep.steps_per_configured_step
        )
        """Physics steps between two instants of the record grid (the ``on_grid`` hook's):
        ``record_every_steps`` of ``sim.timestep_s``, the same instants when the tyres' guard halved
        the timestep."""
        self.grid_us = self.dt_us * self.grid_every
        self.rolling = RollingResistance(self.physics, cfg)
        self.on_grid(self.rolling.update)
        self.on_grid(self.plant.battery.account)
        self.actuation = Actuation(self.plant, self.firmware, self._actuation_hooks)
        self.collisions = CollisionMonitor(
            self.physics, stop=options.stop_on_collision, listeners=self._collision_hooks
        )
        self._grid = GridLoop(self.physics, self.samplers, self.grid_every, self.dt_us)
        self.observables = Observables(
            self.physics, self._grid, self.actuation, self.plant.battery, self.collisions
        )
        """What the twin shows downstream of its loop
        (:class:`~amr_twin.sim.observables.Observables`)."""
        self.halted = False
        self.stopped = False
        """:meth:`stop` was called: :meth:`advance` returns at once (a run ended from outside, e.g.
        a signal)."""
        self.actors = None
        """The actors' motion (:class:`amr_twin.sim.actors.ActorMotion`), None without actors."""
        if options.actors:
            from amr_twin.sim.actors import ActorMotion, ActorPoses

            self.actors = ActorMotion(self.physics, tuple(options.actors), cfg)
            self.on_grid(self.actors.update)
            self._actor_poses = ActorPoses(self.actors, self.clock, self.bus, self.samplers)
        self.on_grid(self.collisions)

    def add_sensor(self, name: str):
        """Build the sensor ``name`` of :data:`~amr_twin.sensors.catalog.SENSORS` on the twin as it
        is now; it samples from the present instant on (its grid samplers run once now). Returns the
        sensor; ValueError (one line) for an unknown name or one the twin has already."""
        from amr_twin.sensors.catalog import SENSORS

        if name in self.sensors:
            raise ValueError(f"sensor {name!r}: the twin has it already")
        factory, n = SENSORS.get(name), len(self.samplers)
        self.sensors[name] = sensor = factory(self._mount, self.cfg)
        for sampler in self.samplers[n:]:
            sampler(self.t_phys_us)
        return sensor

    # -- rosserial bridge ---------------------------------------------------------
    def _to_arduino(self, msg) -> None:
        self.link.send(
            PC_TO_ARDUINO,
            "wheel_Command",
            msg,
            lambda _topic, m: self.firmware.on_wheel_command(list(m.data)),
        )

    def _arduino_publish(self, topic: str, value: float) -> None:
        self.link.send(ARDUINO_TO_PC, topic, Float64(data=float(value)), self.bus.publish)

    # -- time -----------------------------------------------------------------------
    @property
    def t_s(self) -> float:
        return self.clock.now_us / US

    def advance(self, duration_s: float) -> None:
        """Run the twin for ``duration_s`` simulated seconds."""
        if not (math.isfinite(duration_s) and duration_s >= 0):
            raise ValueError(f"duration_s: {duration_s} must be a finite number >= 0")
        self.advance_to_us(self.clock.now_us + int(round(duration_s * US)))

    def advance_to_us(self, t_end_us: int) -> None:
        clock, actuation, event_hooks = self.clock, self.actuation, self._event_hooks
        lookahead = self.bus.lookahead_us
        last_pins = None
        while clock.now_us < t_end_us and not self.halted and not self.stopped:
            t_evt = min(clock.next_synced_event_us(), t_end_us, self._next_check_us)
            t_evt = clock.physics_horizon_us(t_evt, lookahead)
            if self.t_phys_us < t_evt:
                nstep = -(-(t_evt - self.t_phys_us) // self.dt_us)
                self._step_physics(nstep)
                if self.halted:  # a sampler stopped the physics early
                    t_evt = max(clock.now_us, min(t_evt, self.t_phys_us))
            self._deliver_edges(t_evt)
            clock.run_until(t_evt)
            key = actuation.levels()
            if key != last_pins or t_evt >= self._next_check_us:
                actuation.apply(self.t_phys_us)
                last_pins = key
            if t_evt >= self._next_check_us:
                self.physics.check()
                self._next_check_us += int(self.options.check_every_s * US)
            for fn in event_hooks:
                fn(self.t_phys_us)

    def stop(self) -> None:
        """End the run at the next event (safe from a signal handler): :meth:`advance` returns from
        then on."""
        self.stopped = True

    # -- the simulator's interface (amr_twin/ros1/sim_services.py) --------------------------
    def set_robot_pose(self, x_m: float, y_m: float, yaw_rad: float) -> None:
        """Teleport the robot to ``x_m, y_m`` heading ``yaw_rad`` (world frame) at rest
        (:meth:`~amr_twin.sim.physics.Physics.place_robot`); ValueError (one line), the robot left
        where it was, where it would overlap the world."""
        from amr_twin.sim.start_pose import StartPoseError, check_start

        before = self.physics.place_robot(x_m, y_m, yaw_rad, self._rest)
        try:
            check_start(self.physics, f"pose {x_m:g},{y_m:g},{math.degrees(yaw_rad):g}")
        except StartPoseError as exc:
            self.physics.restore_positions(before)
            raise ValueError(str(exc).split(";")[0]) from None

    def set_payload_kg(self, mass_kg: float) -> None:
        """Carry a load of ``mass_kg`` (0: none) from the next step on: a box of ``payload.size_m``
        at ``payload.xy_m`` on the deck (:meth:`~amr_twin.sim.physics.Physics.set_payload_kg`)."""
        from amr_twin.model.robot_spec import payload_centre_m

        self.physics.set_payload_kg(mass_kg, payload_centre_m(self.cfg), self.cfg.payload.size_m)

    def set_charger_a(self, current_a: float) -> None:
        """Connect a charger of ``current_a`` (0: disconnect) to the pack
        (:attr:`~amr_twin.sim.battery.Battery.charger_a`)."""
        self.plant.battery.charger_a = current_a

    def reset_world(self) -> None:
        """The actors back at the start of their paths, the robot at its start pose, at rest."""
        if self.actors is not None:
            self.actors.reset(self.clock.now_us)
        self.set_robot_pose(*self.start_xy_yaw)

    def reset_simulation(self) -> None:
        """:meth:`reset_world`, then the robot's own state: the wheels braked (a stop through the
        client, so the firmware's loop is told as by the menu), the odometry at the origin of
        ``odom``, standing, and an EKF (the navigation stack's) told on the bus that the robot is at
        its start pose. Time runs on."""
        self.reset_world()
        self.client.stop()
        if self.odometry is not None:
            self.odometry.reset(standing=True)
        if getattr(self, "ekf", None) is not None:
            self._publish_placed_pose()

    def _publish_placed_pose(self) -> None:
        """The start pose, known to within :data:`PLACED_SIGMA`, on the EKF's pose input
        (``map_match/pose``)."""
        import numpy as np

        from amr_twin.estimation.ekf import POSE_TOPIC
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
            POSE_TOPIC,
            PoseWithCovarianceStamped(
                Header(0, Time.from_us(self.clock.now_us), "map"),
                PoseWithCovariance(
                    Pose(Point(float(x), float(y), 0.0), Quaternion.from_yaw(float(yaw))), cov
                ),
            ),
        )

    def _step_physics(self, nstep: int) -> None:
        """Step ``nstep`` times, sampling the loop sensors on the record grid
        (:class:`~amr_twin.sim.grid_loop.GridLoop`).

        Hall edge times come from a cubic Hermite interpolation of the sampled
        wheel angles and speeds (exact for constant acceleration; the actuation
        is constant inside a chunk), solved per edge to the microsecond. Plain
        Python lists: a chunk is a handful of samples.
        """
        grid = self._grid
        k, ts, rows, grid_t, grid_rows = grid.run(self.t_phys_us // self.dt_us, nstep)
        self.halted = grid.halted
        self.t_phys_us = k * self.dt_us
        if grid_t:
            for fn in self._grid_row_hooks:
                fn(grid_t, grid_rows)
        edges = self.hall.edges_from_samples(ts, rows)
        if edges:
            self._pending.extend(edges)

    def _deliver_edges(self, t_until_us: int) -> None:
        """Deliver the pending SC edges up to ``t_until_us`` to the firmware's ISR, in time
        order."""
        pending = self._pending
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
