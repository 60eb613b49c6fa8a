"""A world of several robots built from one set of run options: :func:`fleet_world`.

The robots share the options of a :class:`~amr_twin.assembly.twin.TwinOptions` (firmware, world,
sensors, nodes, the record grid, the actors) and differ in their start poses and seeds. They are
built together (:func:`~amr_twin.sim.settled_physics.settled_fleet`: one MjModel, one MjData),
named ``amr-1`` ... ``amr-N`` (:func:`~amr_twin.model.robot_starts.fleet_starts`), and each is a
:class:`~amr_twin.assembly.robot.Robot` of one :class:`~amr_twin.assembly.world.World` with its
own physics view, loop-sensor columns, collision monitor and bus.

Reasons and measurements: docs/explanation/architecture.md#amr_twinassemblyfleet_world.
"""

from __future__ import annotations

from amr_twin.assembly.nodes import NODES
from amr_twin.assembly.robot import RobotSpec
from amr_twin.assembly.world import World
from amr_twin.model.config import TwinConfig
from amr_twin.model.robot_starts import fleet_starts
from amr_twin.model.tyre_stability import announce, tyre_timestep
from amr_twin.sensors.catalog import SENSORS
from amr_twin.sim.settled_physics import settled_fleet


def fleet_world(cfg: TwinConfig, options, poses) -> World:
    """A :class:`~amr_twin.assembly.world.World` of one robot per pose of ``poses`` ((x_m, y_m,
    yaw_rad) each, 2 to :data:`~amr_twin.model.robot_starts.MAX_ROBOTS`), every robot built with
    ``options`` (:class:`~amr_twin.assembly.twin.TwinOptions`; its ``start_xy_yaw`` unused),
    robot ``i`` (0-based) seeded ``options.seed + i``. The visual geoms are kept whatever
    ``options.visuals`` says: the LiDARs and UWB see the other robots by them.

    Raises ValueError (one line) for fewer than two or more than 20 poses, faults (a lone robot's
    only), an unknown sensor or node; :class:`~amr_twin.sim.start_pose.StartPoseError` naming the
    robot for a start that overlaps the world or another robot."""
    poses = list(poses)
    if len(poses) < 2:
        raise ValueError(f"robots: {len(poses)} start poses; a fleet has 2 or more (one: Twin)")
    starts = fleet_starts(poses)
    if options.faults:
        raise ValueError("faults: injected into a lone robot only (Twin), not into a fleet")
    for name in options.sensors:  # an unknown name: before any work
        SENSORS.get(name)
    for name in options.nodes:
        NODES.get(name)
    fleet = settled_fleet(
        cfg,
        options.world,
        starts,
        True,
        "imu" in options.sensors,
        options.settle_s,
        tuple(options.actors),
        tuple(options.obstacles),
    )
    if cfg.sim.floor_friction_field and fleet.world.tyres_engine is not None:
        from amr_twin.sim.floor_friction import draw

        fleet.world.set_floor_friction(draw(cfg, options.seed))  # every robot's tyres
    timestep = tyre_timestep(cfg)
    announce(timestep)
    specs = [
        RobotSpec(
            cfg,
            (s.x_m, s.y_m, s.yaw_rad),
            physics=physics,
            world=options.world,
            firmware=options.firmware,
            firmware_params=options.firmware_params,
            seed=options.seed + i,
            hall_jitter_us=options.hall_jitter_us,
            hall_misalignment_deg=options.hall_misalignment_deg,
            rosserial_extra_latency_us=options.rosserial_extra_latency_us,
            rosserial_loss_prob=options.rosserial_loss_prob,
            sensors=options.sensors,
            nodes=options.nodes,
        )
        for i, (s, physics) in enumerate(zip(starts, fleet.robots))
    ]
    return World(
        fleet.world,
        specs,
        grid_every=max(1, int(options.record_every_steps)) * timestep.steps_per_configured_step,
        check_every_s=options.check_every_s,
        stop_on_collision=options.stop_on_collision,
        actors=tuple(options.actors),
        actor_cfg=cfg,
    )
