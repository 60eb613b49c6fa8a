"""Model build: parameters -> xacro -> URDF (checked by yourdfpy) -> MjSpec -> MJCF.

The URDF carries the geometry, the links, joints and inertias
(:mod:`amr_twin.model.urdf`). What URDF cannot carry is added on the MjSpec
(:mod:`amr_twin.model.robot_spec`): the free joint, the wheel collision ellipsoids, the
caster springs (stiffness, damping, preload), contact parameters, the motor
actuators, sensor sites, the payload and geom groups. This module puts the robot in the
world it stands in, compiles it and exports the URDF and the robot MJCF.
"""

from __future__ import annotations

import contextlib
import math
from dataclasses import dataclass
from pathlib import Path

import mujoco

from amr_twin.model.config import TwinConfig
from amr_twin.model.robot_spec import GROUP_WORLD, IMU_SENSORS, robot_spec
from amr_twin.model.robot_starts import ROBOT_PREFIX, RobotStart
from amr_twin.model.urdf import XACRO_FILE, BuildError, robot_urdf
from amr_twin.model import tyre_numeric as tyres
from amr_twin.model.tyre_stability import tyre_timestep
from amr_twin.model.world_spec import world_compile_error, world_spec

STAND_HEIGHT_M = 0.10
"""How high the ``stand`` world holds the chassis: wheels and casters clear of the floor."""


@dataclass
class Build:
    """Result of :func:`build`: the compiled model, the specs it came from and the robots in it."""

    model: mujoco.MjModel
    spec: mujoco.MjSpec
    robot_spec: mujoco.MjSpec
    urdf: str
    robots: tuple[RobotStart, ...] = ()


def _without_imu(robot: mujoco.MjSpec) -> mujoco.MjSpec:
    """``robot`` without its IMU's MuJoCo sensors: they only read the state, but the
    accelerometer makes every step compute the bodies' accelerations
    (``mj_rnePostConstraint``, ~5 % of a step) for nobody when the IMU is off."""
    for sensor in [s for s in robot.sensors if s.name in IMU_SENSORS]:
        robot.delete(sensor)
    return robot


@contextlib.contextmanager
def _compiling():
    """No Python ``mjcb_passive`` while MuJoCo compiles: it calls the callback with models of its
    own, which the bindings cannot hand to Python (the tyres' Python twin,
    :mod:`amr_twin.sim.tyres`; their C helper needs no such care)."""
    callback = mujoco.get_mjcb_passive()
    if callback is None:
        yield
        return
    mujoco.set_mjcb_passive(None)
    try:
        yield
    finally:
        mujoco.set_mjcb_passive(callback)


def _tyre_contacts(scene: mujoco.MjSpec, cfg: TwinConfig, prefix: str) -> None:
    """The tyres' floor forces by the brush model (:mod:`amr_twin.sim.tyres`): the wheels' contacts
    carry the normal force only (condim 1; their priority makes it win the mix), the model carries
    the tyre parameters (a numeric) and their deflection states (user data). The exported robot
    MJCF keeps the rigid contact: these forces need the twin's callback."""
    for side in ("left", "right"):
        geom = scene.geom(f"{prefix}wheel_{side}_collision")
        geom.condim = 1
        geom.friction = [0.0, 0.0, 0.0]
    name = tyres.numeric_name(prefix)
    scene.add_numeric(name=name, data=tyres.numeric_values(cfg, scene.nuserdata))
    scene.nuserdata += tyres.USERDATA_SIZE


def build(
    cfg: TwinConfig,
    world: str | Path = "warehouse",
    start_xy_yaw: tuple[float, float, float] = (0, 0, 0),
    xacro_file: Path = XACRO_FILE,
    visuals: bool = True,
    imu: bool = True,
    actors: tuple = (),
    obstacles: tuple = (),
    robots: tuple[RobotStart, ...] = (),
) -> Build:
    """Build the robot in a world and compile it (the URDF from :func:`robot_urdf`'s cache).

    ``robots`` (:func:`~amr_twin.model.robot_starts.fleet_starts`): one copy of the robot per
    start, named by its prefix, in order (the start pose ``start_xy_yaw`` is then unused); none:
    the lone robot (``amr/``) at ``start_xy_yaw``.

    ``actors`` (:class:`~amr_twin.model.actors.Actor`) are added as mocap bodies at their poses at
    t = 0, after their speeds and paths are checked against their kinds' ranges and the world's
    free space (:class:`~amr_twin.model.actors.ActorError`, one line).

    ``visuals=False`` leaves the robot's visual geoms out (40 of its 51 geoms, posed every
    step: ~15 % of a step in the empty world) and ``imu=False`` the IMU's sensors: a model
    nothing draws or reads the IMU of, with the same dynamics to the bit. ``obstacles``
    (:class:`~amr_twin.model.worlds.Obstacle`): boxes added to the world (group 0, unmapped).
    """
    urdf = robot_urdf(cfg, xacro_file)
    robot = robot_spec(cfg, urdf, visuals)
    with _compiling():
        robot_xml = robot.to_xml()  # the robot alone, for export, before attaching
    scene = world_spec(cfg, world)
    scene.option.timestep = tyre_timestep(cfg).timestep_s  # the brush tyres' explicit states stable
    for ob in obstacles:
        scene.worldbody.add_geom(
            name=f"obstacle_{ob.name}",
            type=mujoco.mjtGeom.mjGEOM_BOX,
            group=GROUP_WORLD,
            pos=[ob.x_m, ob.y_m, ob.size_m[2] / 2],
            size=[ob.size_m[0] / 2, ob.size_m[1] / 2, ob.size_m[2] / 2],
            quat=[math.cos(ob.yaw_rad / 2), 0, 0, math.sin(ob.yaw_rad / 2)],
            rgba=[0.9, 0.75, 0.1, 1],
        )
    robots = tuple(robots) or (RobotStart(ROBOT_PREFIX, *start_xy_yaw),)
    held = Path(world).stem == "stand"
    for robot_start in robots:
        _attach(scene, robot_xml, robot_start, imu, held)
    if cfg.wheel.tyre_slip:
        for robot_start in robots:
            _tyre_contacts(scene, cfg, robot_start.prefix)
    if actors:
        from amr_twin.model.actors import add_actors, check_speeds

        check_speeds(tuple(actors), cfg)
        add_actors(scene, tuple(actors), cfg)
    try:
        with _compiling():
            model = scene.compile()
    except Exception as exc:
        try:  # the world alone: a fault of the world's file is named with the file
            with _compiling():
                world_spec(cfg, world).compile()
        except Exception:
            raise world_compile_error(world, exc) from None
        raise BuildError(f"MuJoCo compile: {str(exc).splitlines()[0]}") from None
    if cfg.wheel.tyre_slip:
        for robot_start in robots:
            tyres.set_addresses(model, robot_start.prefix)
    if actors:
        from amr_twin.model.actor_space import check_paths

        check_paths(model, tuple(actors), cfg)
    return Build(model=model, spec=scene, robot_spec=robot, urdf=urdf, robots=robots)


def _attach(scene: mujoco.MjSpec, robot_xml: str, at: RobotStart, imu: bool, held: bool) -> None:
    """Attach a copy of the robot (MJCF ``robot_xml``) to ``scene`` at ``at``'s pose, its names
    prefixed; ``held``: welded where it stands (the ``stand`` world, the work station of fig.
    5.1)."""
    x, y, yaw = at.x_m, at.y_m, at.yaw_rad
    z = STAND_HEIGHT_M if held else 0.0
    frame = scene.worldbody.add_frame(
        pos=[x, y, z], quat=[math.cos(yaw / 2), 0, 0, math.sin(yaw / 2)]
    )
    attached = mujoco.MjSpec.from_string(robot_xml)
    scene.attach(attached if imu else _without_imu(attached), prefix=at.prefix, frame=frame)
    if held:
        scene.add_equality(
            type=mujoco.mjtEq.mjEQ_WELD,
            objtype=mujoco.mjtObj.mjOBJ_BODY,
            name1=at.prefix + "base_link",
            name="stand" if at.prefix == ROBOT_PREFIX else at.prefix + "stand",
        )


def _option_fields(opt) -> list[str]:
    """The names of ``mjOption``'s fields (the same on an MjSpec's option and a model's ``opt``)."""
    return [
        name for name in dir(opt) if not name.startswith("_") and not callable(getattr(opt, name))
    ]


def robot_mjcf(result: Build) -> str:
    """The robot MJCF alone, with the physics options its twin model runs with.

    Args:
        result: a :func:`build` result; every ``mjOption`` field of ``result.model.opt`` (timestep
        in s,
            integrator, cone, solver and its iterations, noslip, flags, gravity in m/s^2, magnetic
            field in T, ...) is copied onto ``result.robot_spec``'s option.

    Returns:
        The MJCF text: loaded alone in plain MuJoCo (a floor added) it steps as the twin does, not
        at MuJoCo's defaults (2 ms, Euler), where the stiff caster contacts chatter.
    """
    option = result.robot_spec.option
    for name in _option_fields(result.model.opt):
        setattr(option, name, getattr(result.model.opt, name))
    with _compiling():
        return result.robot_spec.to_xml()


def export(cfg: TwinConfig, urdf_path: Path | None = None, mjcf_path: Path | None = None) -> Build:
    """Write the URDF and the robot MJCF (:func:`robot_mjcf`, with the twin's ``<option>``; the
    committed files are made this way): both or neither
    (:func:`amr_twin.base.atomic_file.all_or_nothing`), never half of one."""
    from amr_twin.base.atomic_file import all_or_nothing, write_text

    result = build(cfg)
    with all_or_nothing():
        for path, text in ((urdf_path, result.urdf), (mjcf_path, robot_mjcf(result))):
            if path is not None:
                write_text(path, text)
    return result
