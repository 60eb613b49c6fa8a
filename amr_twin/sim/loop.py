"""The simulation loop: physics, plant, hall sensors, firmware and PC-side nodes on one clock.

Roles (after dm_control's physics / task / loop): :class:`~amr_twin.sim.physics.Physics`
owns MjData, the firmware and the nodes own their logic, and :class:`Twin` only
orders events in time:

1. find the next *synced* clock event (a timer tick, the end of a ``delay()``, a
   rosserial frame arriving, a sensor reading the physics), the divergence check
   or the end of the run; *publishing* events (odometry, IMU and LiDAR messages,
   :mod:`amr_twin.sim.clock`) do not stop the physics unless a subscriber could act on
   what they publish before it (:meth:`amr_twin.ros.bus.Bus.lookahead_us`);
2. step the physics in C up to that instant with the actuation held, keeping the
   wheel angles on the record grid (every ``record_every_steps``) and handing the
   grid instants to the grid samplers (the rolling resistance from the present
   contact loads, the actors' poses, the IMU's true values, the LiDAR's poses and casts);
3. turn the angles into SC edges (interpolated to the microsecond) and deliver
   them to the firmware's pin-change interrupt in time order, each at its time,
   interleaved with the publishing events that fall in the chunk;
4. run the clock's events; apply the pins to the plant.

A grid sampler that returns True (the collision monitor with ``stop_on_collision``)
ends the chunk at that grid instant and halts the twin: :meth:`Twin.advance` does
nothing more (:attr:`Twin.halted`).

A synced event at ``t`` acts from the first physics step that starts at or after
``t``; a publishing event runs at its own time, possibly with the physics ahead.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from itertools import islice

import mujoco
import numpy as np

from amr_twin.model.robot_spec import LOOP_SENSOR_DIM
from amr_twin.ros.bus import Bus
from amr_twin.sim.clock import VirtualClock
from amr_twin.sim.collisions import CollisionMonitor
from amr_twin.sim.grid_steps import grid_stepper
from amr_twin.model.config import TwinConfig
from amr_twin.controllers.firmware import make_firmware
from amr_twin.controllers.odometry import WheelOdometry
from amr_twin.controllers.wheel_command import WheelCommandClient, WheelCommandService
from amr_twin.ros.messages import Float64
from amr_twin.sim.settled_physics import settled_physics
from amr_twin.sim.plant import Plant
from amr_twin.recording.recorder import Recorder
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
    start_xy_yaw: tuple[float, float, float] | None = (0.0, 0.0, 0.0)  # x_m, y_m, yaw_rad; None: the world's
    # own start (amr_twin.model.worlds.default_start: the warehouse's is the west end of its central aisle; the CLI's default)
    settle_s: float = 0.5
    record_every_steps: int = 10  # time series at 100 Hz with 1 ms steps
    hall_jitter_us: float = 0.0
    hall_misalignment_deg: float = 0.0
    rosserial_extra_latency_us: int = 0
    rosserial_loss_prob: float = 0.0
    check_every_s: float = 0.5  # divergence check period
    sensors: bool = False  # IMU (imu/data_raw, imu/mag) and LiDAR (scan) on the clock
    stop_on_collision: bool = False  # halt the twin at the first collision (amr_twin.sim.collisions)
    odometry: bool = True  # the wheel odometry node (odom, tf); off for runs nothing reads it from (a sweep
    # point): it only publishes, so the drive is the same to the bit without it
    faults: tuple = ()  # amr_twin.sim.faults.Fault items, injected at their times
    obstacles: tuple = ()  # amr_twin.model.worlds.Obstacle boxes added to the world (unmapped: no map holds them)
    visuals: bool = True  # the robot's visual geoms in the model; off for runs nothing draws (no .rrd, no live
    # view): they collide with nothing and weigh nothing, so the dynamics are the same to the bit, ~15 % cheaper
    actors: tuple = ()  # amr_twin.model.actors.Actor items: people and pallet jacks moved on the grid
    # (amr_twin.sim.actors), their true poses on actors/poses
    firmware_params: object = field(default=None, compare=False)
    odometry_calibration: object = None  # controllers/odometry_calibration.OdometryCalibration: the odometry
    # node's effective wheel radii and wheelbase (a UMBmark calibration); None: the nominal geometry


class Twin:
    """The whole robot: build it, then :meth:`advance` it in simulated time."""

    def __init__(self, cfg: TwinConfig, options: TwinOptions = TwinOptions()):
        from amr_twin.model.worlds import default_start

        self.cfg, self.options = cfg, options
        start = options.start_xy_yaw if options.start_xy_yaw is not None else default_start(options.world)
        self.start_xy_yaw = tuple(float(v) for v in start)
        pose = f"{start[0]:g},{start[1]:g},{math.degrees(start[2]):g}"
        where = (f"--start {pose} in world {options.world}" if options.start_xy_yaw is not None
                 else f"the start pose {pose} of world {options.world}")
        physics, urdf = settled_physics(cfg, options.world, self.start_xy_yaw, options.visuals, options.sensors,
                                        options.settle_s, where, tuple(options.actors), options.obstacles)
        self.physics = physics
        self.floor = None
        """The floor's friction field of this run (:mod:`amr_twin.sim.floor_friction`), drawn from the
        seed with ``sim.floor_friction_field`` and the brush tyres; None otherwise."""
        if cfg.sim.floor_friction_field and physics.tyres_engine is not None:
            from amr_twin.sim.floor_friction import draw

            self.floor = draw(cfg, options.seed)
            physics.set_floor_friction(self.floor)
        self.urdf = urdf
        """The robot description as built (``/robot_description`` of a recording)."""
        self.dt_us = int(round(self.physics.timestep_s * US))
        self.t_phys_us = 0
        self.clock = VirtualClock()
        self.bus = Bus(self.clock)
        self.bus.send_transform(robot_static_transforms(self.physics.model), static=True)  # laser, imu_link, uwb_tag
        self.link = RosserialLink(self.clock, extra_latency_us=options.rosserial_extra_latency_us,
                                  loss_prob=options.rosserial_loss_prob, seed=options.seed)
        self.plant = Plant(cfg, self.physics)
        self.hall = HallSensors(2, misalignment_deg=options.hall_misalignment_deg,
                                jitter_us=options.hall_jitter_us, seed=options.seed,
                                hysteresis_deg=cfg.wheel.hall_hysteresis_deg)
        self.hall.reset(self.physics.wheel_angles_rad())
        self.firmware = make_firmware(options.firmware, self.clock, self._arduino_publish,
                                      options.firmware_params)
        # PC side (the mini PC): service, client, odometry; rosserial bridges to the Arduino
        self.service = WheelCommandService(self.bus)
        self.client = WheelCommandClient(self.bus, wheel_radius_m=cfg.wheel.radius_m,
                                         half_separation_m=cfg.wheel.separation_m / 2)
        if hasattr(self.firmware, "connect"):  # it speaks rosserial on its own (emulated) UART
            self.firmware.connect(self.bus, self.link)
        else:
            self.bus.subscribe("wheel_Command", self._to_arduino)
        calibration = options.odometry_calibration
        self.odometry = (WheelOdometry(self.bus, self.clock, wheel_radius_m=cfg.wheel.radius_m,
                                       wheel_separation_m=cfg.wheel.separation_m,
                                       **({} if calibration is None else
                                          calibration.multipliers(cfg.wheel.radius_m, cfg.wheel.separation_m)))
                         if options.odometry else None)
        self.recorder = Recorder(self)
        self.grid_us = self.dt_us * self.recorder.every
        self.rolling = RollingResistance(self.physics, cfg)
        self.samplers: list = [self.rolling.update, self.plant.battery.account, self.recorder.battery]
        """Callables ``f(t_us)`` run on the record grid while the physics steps (physics at ``t_us``):
        the rolling resistance from the present loads, the battery and the recorder's copy of its
        state, the collision monitor, the sensors' samplers. One that returns True halts the twin there."""
        self.halted = False
        self.actors = None
        """The actors' motion (:class:`amr_twin.sim.actors.ActorMotion`), None without actors."""
        if options.actors:
            from amr_twin.sim.actors import ActorMotion, ActorPoses
            self.actors = ActorMotion(self.physics, tuple(options.actors), cfg)
            self.samplers.append(self.actors.update)
            self._actor_poses = ActorPoses(self.actors, self.clock, self.bus, self.samplers)
        self.collisions = CollisionMonitor(self.physics, stop=options.stop_on_collision)
        self.samplers.append(self.collisions)
        if options.sensors:  # Adafruit 9-DOF IMU and RPLIDAR A1 (sensors/imu.py, sensors/lidar.py)
            from amr_twin.sensors.imu import ImuSensor
            from amr_twin.sensors.lidar import Lidar
            m, d = self.physics.model, self.physics.data
            self.imu = ImuSensor(m, d, self.clock, self.bus, cfg.imu, seed=[options.seed, 1],
                                 autostart=False)
            self.imu.start(grid_us=self.grid_us, samplers=self.samplers)
            # with actors moving, a cast every 20 ms (each beam sees them within ~2 cm of where they
            # were at its instant) rather than one a rotation (up to 0.27 m off for a walker)
            self.lidar = Lidar(m, d, self.clock, self.bus, cfg.lidar, seed=[options.seed, 2],
                               autostart=False, **({"loop_cast_us": 20_000} if options.actors else {}))
            self.lidar.start_motor(grid_us=self.grid_us, samplers=self.samplers)
        self._stepper = grid_stepper(self.physics, LOOP_SENSOR_DIM, self.recorder.every, self.dt_us)
        """The grid loop in C (:mod:`amr_twin.sim.grid_steps`), None without its helper."""
        self._pending: list[tuple[int, int]] = []  # SC edges (t_us, wheel) not yet delivered
        self._loop_sensors = self.physics.data.sensordata[:LOOP_SENSOR_DIM]  # a view: MjData's buffers stay put
        self._last_row = self._loop_sensors.tolist()
        self._next_check_us = int(options.check_every_s * US)
        for sampler in self.samplers:
            sampler(0)
        self.faults = None
        if options.faults:
            from amr_twin.sim.fault_injector import FaultInjector
            self.faults = FaultInjector(self, options.faults)
        self.firmware.start()
        self.plant.apply(self.firmware.pins)
        self.recorder.pins_changed(0)
        self.recorder.sample()

    # -- rosserial bridge ---------------------------------------------------------
    def _to_arduino(self, msg) -> None:
        self.link.send(PC_TO_ARDUINO, "wheel_Command", msg,
                       lambda _topic, m: self.firmware.on_wheel_command(list(m.data)))

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
        clock, fw, plant = self.clock, self.firmware, self.plant
        lookahead = self.bus.lookahead_us
        last_pins = None
        while clock.now_us < t_end_us and not self.halted:
            t_evt = min(clock.next_synced_event_us(), t_end_us, self._next_check_us)
            t_evt = clock.physics_horizon_us(t_evt, lookahead)
            if self.t_phys_us < t_evt:
                nstep = -(-(t_evt - self.t_phys_us) // self.dt_us)
                self._step_physics(nstep)
                if self.halted:  # a sampler stopped the physics early
                    t_evt = max(clock.now_us, min(t_evt, self.t_phys_us))
            self._deliver_edges(t_evt)
            clock.run_until(t_evt)
            pins = fw.pins
            key = (pins[0].pwm_counts, pins[0].dir_level, pins[0].brake_level, pins[0].stop_level,
                   pins[1].pwm_counts, pins[1].dir_level, pins[1].brake_level, pins[1].stop_level)
            if key != last_pins or t_evt >= self._next_check_us:
                plant.apply(pins)
                self.recorder.pins_changed(self.t_phys_us)
                last_pins = key
            if t_evt >= self._next_check_us:
                self.physics.check()
                self._next_check_us += int(self.options.check_every_s * US)

    def _step_physics(self, nstep: int) -> None:
        """Step ``nstep`` times in C, sampling the loop sensors on the record grid.

        Hall edge times come from a cubic Hermite interpolation of the sampled
        wheel angles and speeds (exact for constant acceleration; the actuation
        is constant inside a chunk), solved per edge to the microsecond. Plain
        Python lists: a chunk is a handful of samples. The grid loop runs in C when
        every grid sampler has a C form (:meth:`_grid_in_c`), else here (:meth:`_grid_in_python`).
        """
        dt = self.dt_us
        k0 = self.t_phys_us // dt
        k_end = k0 + nstep
        grid_t, grid_rows = [], []
        stepper = self._stepper
        if stepper is not None and stepper.use(self.samplers):
            k = self._grid_in_c(stepper, k0, k_end, grid_t, grid_rows)
        else:
            k = self._grid_in_python(k0, k_end, grid_t, grid_rows)
        if self.halted:  # a sampler stopped the physics at step k
            k_end = k
        ts, rows = [k0 * dt, *grid_t], [self._last_row, *grid_rows]
        if k < k_end:
            mujoco.mj_step(self.physics.model, self.physics.data, k_end - k)
            k = k_end
            ts.append(k * dt)
            rows.append(self._loop_sensors.tolist())
        self.t_phys_us = k * dt
        self._last_row = rows[-1]
        if grid_t:
            self.recorder.extend_grid(grid_t, grid_rows)
        edges = self.hall.edges_from_samples(ts, rows)
        if edges:
            self._pending.extend(edges)

    def _grid_in_python(self, k: int, k_end: int, grid_t: list, grid_rows: list) -> int:
        """From step ``k``, step to each grid instant up to step ``k_end``, keeping its time and
        row in ``grid_t`` and ``grid_rows`` and running the grid samplers there; the step reached
        (the last instant's, or ``k``). A sampler returning True halts the twin at its instant."""
        m, d, dt, every = self.physics.model, self.physics.data, self.dt_us, self.recorder.every
        sensors, step, samplers = self._loop_sensors, mujoco.mj_step, self.samplers
        for mark in range((k // every + 1) * every, k_end + 1, every):
            step(m, d, mark - k)
            k = mark
            t = k * dt
            row = sensors.tolist()
            grid_t.append(t)
            grid_rows.append(row)
            stop = False
            for sampler in samplers:
                if sampler(t):
                    stop = True
            if stop:
                self.halted = True
                break
        return k

    def _grid_in_c(self, stepper, k: int, k_end: int, grid_t: list, grid_rows: list) -> int:
        """:meth:`_grid_in_python` with the grid loop in C (:mod:`amr_twin.sim.grid_steps`): the same
        steps, rows and sampler calls. An instant a sampler hands back runs the rest of its
        samplers here; if one then has no C form (a collision opened) the chunk ends in Python."""
        dt, every = self.dt_us, self.recorder.every
        first = (k // every + 1) * every
        nmarks = (k_end - first) // every + 1 if first <= k_end else 0
        done = 0
        while done < nmarks:
            mark = first + done * every
            reached, handoff = stepper.run(mark - k, nmarks - done, mark * dt)
            k = mark + (reached - 1) * every
            grid_t.extend(range(mark * dt, k * dt + 1, every * dt))
            grid_rows.extend(stepper.rows[:reached].tolist())
            done += reached
            if handoff >= 0:
                t = k * dt
                stop = bool(stepper.resume[handoff](t))
                for sampler in islice(self.samplers, handoff + 1, None):  # the live list, as the Python loop walks it
                    if sampler(t):
                        stop = True
                if stop:
                    self.halted = True
                    return k
                if done < nmarks and not stepper.use(self.samplers):
                    return self._grid_in_python(k, k_end, grid_t, grid_rows)
        return k

    def _deliver_edges(self, t_until_us: int) -> None:
        """Deliver the pending SC edges up to ``t_until_us`` to the firmware's ISR, in time order."""
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
