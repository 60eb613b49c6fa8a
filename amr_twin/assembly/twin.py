"""The twin assembled: the simulation loop with its physics, plant, hall sensors, firmware and
PC-side nodes on one clock.

Reasons and measurements: docs/explanation/architecture.md#amr_twinassemblytwin."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from amr_twin.assembly.nodes import NODES
from amr_twin.assembly.robot import RobotSpec
from amr_twin.assembly.world import World
from amr_twin.model.config import TwinConfig
from amr_twin.model.tyre_stability import announce, tyre_timestep
from amr_twin.sensors.catalog import SENSORS
from amr_twin.sim.settled_physics import settled_physics


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
    nodes: tuple[str, ...] = ("odometry",)  # PC-side nodes by name
    # (amr_twin.assembly.nodes.NODES): "odometry" (odom, tf); () for runs nothing reads them from (a
    # sweep point): they only publish, so the drive is the same to the bit without them
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
        if type(self.nodes) is not tuple or not all(type(name) is str for name in self.nodes):
            raise ValueError(
                f"nodes: {self.nodes!r} must be a tuple of node names, e.g. ('odometry',)"
            )


class Twin(World):
    """The whole robot: a :class:`~amr_twin.assembly.world.World` with one
    :class:`~amr_twin.assembly.robot.Robot` (:attr:`robot`); build it, then :meth:`advance` it in
    simulated time.

    Code downstream of the loop subscribes to its hooks (:class:`~amr_twin.sim.hooks.Hooks`:
    ``on_grid``, ``on_grid_rows``, ``on_event``, ``on_actuation``, ``on_message``) and reads
    :attr:`observables`; it does not reach into :attr:`physics`, :attr:`plant`, :attr:`hall`
    or :attr:`firmware` (tests/sim/test_hooks.py). The robot's parts are the twin's attributes
    too: :attr:`link`, :attr:`plant`, :attr:`hall`, :attr:`firmware`, :attr:`service`,
    :attr:`client`, :attr:`nodes`, :attr:`rolling`, :attr:`actuation`, :attr:`sensors` (built
    from ``options.sensors``, :data:`amr_twin.sensors.catalog.SENSORS`), :attr:`observables`,
    :attr:`faults`."""

    def __init__(self, cfg: TwinConfig, options: TwinOptions = TwinOptions()):
        for name in options.sensors:  # an unknown name: before any work
            SENSORS.get(name)
        for name in options.nodes:
            NODES.get(name)
        self.cfg, self.options = cfg, options
        physics, start = self._build_physics(cfg, options)
        calibration = options.odometry_calibration
        spec = RobotSpec(
            cfg,
            start,
            world=options.world,
            firmware=options.firmware,
            firmware_params=options.firmware_params,
            seed=options.seed,
            hall_jitter_us=options.hall_jitter_us,
            hall_misalignment_deg=options.hall_misalignment_deg,
            rosserial_extra_latency_us=options.rosserial_extra_latency_us,
            rosserial_loss_prob=options.rosserial_loss_prob,
            sensors=options.sensors,
            nodes=options.nodes,
            node_params={} if calibration is None else {"odometry": {"calibration": calibration}},
            faults=tuple(options.faults),
        )
        super().__init__(
            physics,
            [spec],
            grid_every=max(1, int(options.record_every_steps))
            * self.tyre_timestep.steps_per_configured_step,
            check_every_s=options.check_every_s,
            stop_on_collision=options.stop_on_collision,
            actors=tuple(options.actors),
            actor_cfg=cfg,
        )
        self.robot = robot = self.robots[0]
        """The one robot (:class:`~amr_twin.assembly.robot.Robot`)."""
        self.start_xy_yaw = robot.start_xy_yaw
        self.link, self.plant, self.hall, self.firmware = (
            robot.link,
            robot.plant,
            robot.hall,
            robot.firmware,
        )
        self.service, self.client, self.nodes = robot.service, robot.client, robot.nodes
        self.rolling, self.actuation, self.sensors = robot.rolling, robot.actuation, robot.sensors
        self.observables, self.faults = robot.observables, robot.faults

    def _build_physics(self, cfg: TwinConfig, options: TwinOptions) -> tuple:
        """The robot in its world at its start pose, settled; the floor's friction field; the
        timestep. Returns the physics and the start pose (m, m, rad)."""
        from amr_twin.model.worlds import default_start

        start = (
            options.start_xy_yaw
            if options.start_xy_yaw is not None
            else default_start(options.world)
        )
        start = tuple(float(v) for v in start)
        pose = f"{start[0]:g},{start[1]:g},{math.degrees(start[2]):g}"
        where = (
            f"--start {pose} in world {options.world}"
            if options.start_xy_yaw is not None
            else f"the start pose {pose} of world {options.world}"
        )
        physics, urdf = settled_physics(
            cfg,
            options.world,
            start,
            options.visuals,
            "imu" in options.sensors,
            options.settle_s,
            where,
            tuple(options.actors),
            options.obstacles,
        )
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
        return physics, start

    def add_sensor(self, name: str):
        """Build the sensor ``name`` on the robot as it is now
        (:meth:`~amr_twin.assembly.robot.Robot.add_sensor`); returns it."""
        return self.robot.add_sensor(name)

    # -- the simulator's interface (amr_twin/ros1/sim_services.py) --------------------------
    def set_robot_pose(self, x_m: float, y_m: float, yaw_rad: float) -> None:
        """Teleport the robot (:meth:`~amr_twin.assembly.robot.Robot.set_pose`)."""
        self.robot.set_pose(x_m, y_m, yaw_rad)

    def set_payload_kg(self, mass_kg: float) -> None:
        """Carry a load of ``mass_kg`` (:meth:`~amr_twin.assembly.robot.Robot.set_payload_kg`)."""
        self.robot.set_payload_kg(mass_kg)

    def set_charger_a(self, current_a: float) -> None:
        """Connect a charger (:meth:`~amr_twin.assembly.robot.Robot.set_charger_a`)."""
        self.robot.set_charger_a(current_a)

    def reset_simulation(self) -> None:
        """:meth:`reset_world`, then the robot's own state
        (:meth:`~amr_twin.assembly.robot.Robot.reset_state`), and an EKF (the navigation stack's)
        told on the bus that the robot is at its start pose. Time runs on."""
        self.reset_world()
        self.robot.reset_state()
        if getattr(self, "ekf", None) is not None:
            from amr_twin.estimation.ekf import POSE_TOPIC

            self.robot.publish_placed_pose(POSE_TOPIC)
