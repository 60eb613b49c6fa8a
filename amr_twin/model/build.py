"""Model build: parameters -> xacro -> URDF (checked by yourdfpy) -> MjSpec -> MJCF.

The URDF carries the geometry, the links, joints and inertias. What URDF cannot
carry is added on the MjSpec: the free joint, the wheel collision ellipsoids, the
caster springs (stiffness, damping, preload), contact parameters, the motor
actuators, sensor sites, the payload, geom groups, and the world it stands in.

The first eleven sensor values are read by the loop every step
(:data:`LOOP_SENSOR_DIM`): wheel angles L, R; wheel speeds L, R; base position;
base quaternion.

Geom groups (``geomgroup`` masks): 0 world, 1 robot visuals, 2 robot collision,
4 payload. A LiDAR casts against groups 0 and 4 so that it never sees the robot's
own wheels and casters but does see a payload in its scan plane.
"""

from __future__ import annotations

import contextlib
import hashlib
import io
import json
import math
import os
import tempfile
from dataclasses import dataclass
from pathlib import Path

import mujoco
import numpy as np
import yaml

from amr_twin.model import mass
from amr_twin.model.config import TwinConfig
from amr_twin.model.paths import MODEL_DIR, ROOT

XACRO_FILE = MODEL_DIR / "amr.urdf.xacro"
WORLD_DIR = ROOT / "models" / "worlds"
GROUP_WORLD, GROUP_VISUAL, GROUP_COLLISION, GROUP_PAYLOAD = 0, 1, 2, 4
WHEELS = ("left", "right")
CASTERS = ("front_left", "front_right", "rear_left", "rear_right")
ROBOT_PREFIX = "amr/"
LOOP_SENSOR_DIM = 11
STAND_HEIGHT_M = 0.10
"""How high the ``stand`` world holds the chassis: wheels and casters clear of the floor."""


CACHE_ENV = "AMR_TWIN_CACHE_DIR"
"""Environment variable naming the folder of the URDF cache (default ``$XDG_CACHE_HOME/amr-twin``,
``~/.cache/amr-twin``); an empty value turns the disk cache off."""
CACHE_FORMAT = 1
"""Part of every cache key: raise it when what a cached URDF means changes."""
_urdf_memo: dict[str, str] = {}


class BuildError(RuntimeError):
    """The model could not be built; the message is one line."""


def derived_params(cfg: TwinConfig) -> dict:
    """The flat parameter set the xacro reads (geometry, inertias, limits)."""
    c, w, k = cfg.chassis, cfg.wheel, cfg.caster
    p = {
        "chassis_length_m": c.length_m, "chassis_width_m": c.width_m,
        "floor_a_z_m": c.floor_a_z_m, "floor_b_z_m": c.floor_b_z_m, "floor_c_z_m": c.floor_c_z_m,
        "tube_outer_m": c.tube_outer_m, "sheet_thickness_m": c.sheet_thickness_m,
        "deck_thickness_m": cfg.deck.thickness_m,
        # the true geometry: the nominal radius and separation plus the tyres' errors (wheel.*_error_*)
        "wheel_radius_m": w.radius_m, "wheel_width_m": w.width_m,
        "wheel_separation_m": w.separation_m + w.separation_error_m,
        "wheel_left_radius_m": w.radius_of("left"), "wheel_right_radius_m": w.radius_of("right"),
        "wheel_torque_limit_nm": max(m.ke_v_s_rad * m.current_limit_a for m in (cfg.motor_left, cfg.motor_right)),
        "wheel_speed_limit_rad_s": cfg.battery.v_full_v / min(cfg.motor_left.ke_v_s_rad, cfg.motor_right.ke_v_s_rad),
        "caster_ball_diameter_m": k.ball_diameter_m, "caster_x_m": k.x_m, "caster_y_m": k.y_m,
        "caster_travel_m": k.travel_m, "caster_drop_m": k.drop_m,
        # what URDF can say of the MJCF's joint dynamics (<dynamics>, <limit>): set again on the MjSpec below
        "wheel_left_damping": cfg.motor_left.damping_nm_s_rad, "wheel_left_friction": cfg.motor_left.friction_nm,
        "wheel_right_damping": cfg.motor_right.damping_nm_s_rad, "wheel_right_friction": cfg.motor_right.friction_nm,
        "caster_damping_n_s_m": k.damping_n_s_m, "caster_effort_n": k.preload_n + k.stiffness_n_m * k.travel_m,
        "uwb_tag_pos_m": list(cfg.uwb.tag_pos_m), "uwb_tag_size_m": list(cfg.uwb.tag_size_m),
    }
    for name, comp in cfg.components.items():
        p[f"{name}_size_m"] = list(comp.size_m)
        p[f"{name}_pos_m"] = list(comp.pos_m)
    sensors = mass.sensor_link_inertials(cfg)
    for prefix, inertial in (("chassis", mass.chassis_inertial(cfg)), ("wheel", mass.wheel_inertial(cfg)),
                             ("caster", mass.caster_inertial(cfg)), ("laser", sensors["laser"]),
                             ("imu_link", sensors["imu_link"]), ("uwb_tag", sensors["uwb_tag"])):
        p[f"{prefix}_mass_kg"] = inertial.mass_kg
        p[f"{prefix}_com_m"] = [float(v) for v in inertial.com_m]
        p[f"{prefix}_inertia"] = [float(v) for v in inertial.diag()]
    return {key: (float(v) if isinstance(v, (int, float, np.floating)) else v) for key, v in p.items()}


def urdf_string(cfg: TwinConfig, xacro_file: Path = XACRO_FILE) -> str:
    """Run xacro on the robot description with the resolved parameters."""
    import xacro  # imported here: slow, and only needed to build

    with tempfile.NamedTemporaryFile("w", suffix=".yaml", delete=False) as fh:
        yaml.safe_dump(derived_params(cfg), fh)
        params_path = fh.name
    try:
        doc = xacro.process_file(str(xacro_file), mappings={"params": params_path})
    except Exception as exc:  # XacroException, XML parse errors, missing file
        first = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
        raise BuildError(f"xacro {xacro_file.name}: {first}") from None
    finally:
        Path(params_path).unlink(missing_ok=True)
    text = doc.toprettyxml(indent="  ")
    # xacro names its absolute source path in a header comment: keep the file portable
    source = Path(xacro_file).resolve()
    shown = source.relative_to(ROOT).as_posix() if source.is_relative_to(ROOT) else source.name
    return text.replace(str(xacro_file), shown).replace(str(source), shown)


def urdf_cache_dir() -> Path | None:
    """The URDF cache's folder (:data:`CACHE_ENV`), or None when the disk cache is off."""
    configured = os.environ.get(CACHE_ENV)
    if configured is not None:
        return Path(configured) / "urdf" if configured.strip() else None
    base = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(base) / "amr-twin" / "urdf"


def urdf_fingerprint(cfg: TwinConfig, xacro_file: Path = XACRO_FILE) -> str:
    """Key of the robot description: the xacro source and the parameters it reads (not the
    payload, the motors' electrics or anything else added on the MjSpec), sha256."""
    text = Path(xacro_file).read_text()
    digest = hashlib.sha256()
    builder = Path(__file__).read_bytes()  # this module makes the URDF from the xacro's output
    for part in (f"format {CACHE_FORMAT}", str(xacro_file), text, json.dumps(derived_params(cfg), sort_keys=True)):
        digest.update(part.encode())
        digest.update(b"\0")
    digest.update(builder)
    return digest.hexdigest()[:32]


def robot_urdf(cfg: TwinConfig, xacro_file: Path = XACRO_FILE) -> str:
    """The robot's URDF (:func:`urdf_string`), validated (:func:`check_urdf`) once per fingerprint.

    Cached in this process and on disk (:func:`urdf_cache_dir`): a payload sweep or a
    second run of the same robot skips xacro (~45 ms) and yourdfpy (~20 ms, and its trimesh
    import, ~0.8 s). A cached file is written only after the check passed, by one rename.
    """
    try:
        key = urdf_fingerprint(cfg, xacro_file)
    except OSError as exc:
        raise BuildError(f"xacro {Path(xacro_file).name}: {exc.strerror or exc}") from None
    urdf = _urdf_memo.get(key)
    if urdf is not None:
        return urdf
    folder = urdf_cache_dir()
    path = folder / f"{key}.urdf" if folder is not None else None
    try:
        urdf = path.read_text() if path is not None else None
    except (OSError, UnicodeDecodeError):
        urdf = None
    if not urdf:
        urdf = urdf_string(cfg, xacro_file)
        check_urdf(urdf)
        if path is not None:
            _store(path, urdf)
    _urdf_memo[key] = urdf
    return urdf


def _store(path: Path, text: str) -> None:
    """Write a cache file whole (temporary, then rename); a cache that cannot be written is skipped."""
    tmp = None
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
        with os.fdopen(fd, "w") as fh:
            fh.write(text)
        os.replace(tmp, path)
    except OSError:
        if tmp is not None:
            with contextlib.suppress(OSError):
                os.unlink(tmp)


def check_urdf(urdf: str) -> None:
    """Load and validate the URDF with yourdfpy; raise BuildError if it is invalid."""
    import yourdfpy

    try:
        robot = yourdfpy.URDF.load(io.StringIO(urdf), load_meshes=False, build_scene_graph=True)
    except Exception as exc:
        raise BuildError(f"URDF: {str(exc).splitlines()[0]}") from None
    if not robot.validate():
        raise BuildError("URDF: yourdfpy validation failed")
    if robot.base_link != "base_link":
        raise BuildError(f"URDF: root link is {robot.base_link!r}, expected 'base_link'")


def _robot_spec(cfg: TwinConfig, urdf: str) -> mujoco.MjSpec:
    """The robot alone: URDF import plus everything URDF cannot carry."""
    # MuJoCo's URDF parser reads its options from a <mujoco> element in the URDF:
    # keep the visuals (it discards them by default) and every link as a body.
    options = '<mujoco><compiler discardvisual="false" fusestatic="false" strippath="true"/></mujoco>'
    spec = mujoco.MjSpec.from_string(urdf.replace("</robot>", options + "</robot>", 1))
    spec.modelname = "amr"
    # Elliptic friction cones: the contact's first constraint row is its normal force
    # (read by Physics.support_normal_forces_n); exported with the robot.
    spec.option.cone = mujoco.mjtCone.mjCONE_ELLIPTIC
    _tag_geoms(spec, cfg)
    base = spec.body("base_link")
    base.add_freejoint(name="root")
    _add_casters(spec, cfg)
    _add_wheels(spec, cfg)
    _add_payload(spec, base, cfg)
    imu = spec.body("imu_link")
    imu.add_site(name="imu", size=[0.01, 0.01, 0.002], type=mujoco.mjtGeom.mjGEOM_BOX, group=GROUP_VISUAL)
    spec.body("laser").add_site(name="laser", size=[0.01, 0, 0], group=GROUP_VISUAL)
    base.add_site(name="base", size=[0.01, 0, 0], group=GROUP_VISUAL)
    _add_sensors(spec)
    return spec


def _tag_geoms(spec: mujoco.MjSpec, cfg: TwinConfig) -> None:
    """Visual geoms collide with nothing (group 1); collision geoms go to group 2."""
    for geom in spec.geoms:
        if geom.contype == 0 and geom.conaffinity == 0:
            geom.group = GROUP_VISUAL
        else:
            geom.group = GROUP_COLLISION
            geom.rgba = [0.5, 0.5, 0.5, 0.0]


def _collision_geom(body: mujoco.MjsBody) -> mujoco.MjsGeom:
    geoms = [g for g in body.geoms if g.group == GROUP_COLLISION]
    if len(geoms) != 1:
        raise BuildError(f"body {body.name}: expected one collision geom, found {len(geoms)}")
    return geoms[0]


CONTACT_SOLREF = (0.002, 1.0)
CONTACT_SOLIMP = (0.97, 0.97, 0.001, 0.5, 2.0)
"""solref (time constant s, damping ratio) and solimp of the wheel and caster contacts:
as stiff as the 1 ms step allows (MuJoCo recommends a time constant of at least twice
the timestep; an impedance of 0.98 made the caster balls chatter). A support then
sinks a few micrometres into the floor, so the load split follows the physical
springs (tyres, caster springs) within 0.4 % of the hand calculation of
:mod:`amr_twin.model.statics`, not the solver's softness (default solref/solimp: 1.4 %)."""


def _add_wheels(spec: mujoco.MjSpec, cfg: TwinConfig) -> None:
    w = cfg.wheel
    g = cfg.sim.gravity_m_s2
    rotor_kg = mass.wheel_inertial(cfg).mass_kg
    for side, motor in zip(WHEELS, (cfg.motor_left, cfg.motor_right)):
        body = spec.body(f"wheel_{side}_link")
        geom = _collision_geom(body)
        # An ellipsoid keeps a single contact point under the hub while spinning in
        # place (a cylinder micro-hops, stack-notes.md); its local z is the axle.
        geom.type = mujoco.mjtGeom.mjGEOM_ELLIPSOID
        geom.size = [w.radius_of(side), w.radius_of(side), w.width_m / 2]
        # sliding friction only; the tyre's rolling resistance is a load-dependent
        # torque (amr_twin.sim.rolling_resistance): MuJoCo's rolling friction (condim 6)
        # made these stiff contacts chatter
        geom.condim = 3
        geom.friction = [w.friction, 0.0, 0.0]
        geom.priority = 1  # the tyre's contact parameters win over the floor's
        geom.solref, geom.solimp = list(CONTACT_SOLREF), list(CONTACT_SOLIMP)
        geom.name = f"wheel_{side}_collision"
        # The tyre's radial compliance: a vertical slide between hub and chassis, before
        # the axle hinge so that it does not turn with the wheel; q > 0 = tyre compressed.
        # springref = m_rotor g / k: the spring then carries the tyre's whole load, so the
        # compression is N / k as for a real tyre, and a lifted wheel hangs at q = 0.
        hinge = spec.joint(f"wheel_{side}_joint")
        spec.delete(hinge)
        tyre = body.add_joint(name=f"wheel_{side}_tyre", type=mujoco.mjtJoint.mjJNT_SLIDE, axis=[0, 0, 1])
        tyre.stiffness[0] = w.tyre_stiffness_n_m
        tyre.damping[0] = w.tyre_damping_n_s_m
        tyre.springref = rotor_kg * g / w.tyre_stiffness_n_m
        joint = body.add_joint(name=f"wheel_{side}_joint", type=mujoco.mjtJoint.mjJNT_HINGE, axis=[0, 1, 0])
        # The URDF effort limit would become a joint-level clamp of all actuator torque in
        # MuJoCo; the driver's current limit is the actuator's forcerange instead, so
        # that a shorted (braking) motor is limited by its own current, not the driver's.
        joint.actfrclimited = 0
        joint.damping[0] = motor.damping_nm_s_rad
        joint.frictionloss = motor.friction_nm
        kt_over_r = motor.ke_v_s_rad / motor.resistance_ohm  # Kt = Ke in SI units
        act = spec.add_actuator(name=f"motor_{side}", target=joint.name,
                                trntype=mujoco.mjtTrn.mjTRN_JOINT)
        # Quasi-static DC motor in C: torque = Kt/R * v - Kt*Ke/R * omega (ctrl = phase voltage, V)
        act.gaintype = mujoco.mjtGain.mjGAIN_FIXED
        act.biastype = mujoco.mjtBias.mjBIAS_AFFINE
        act.gainprm[0] = kt_over_r
        act.biasprm[2] = -kt_over_r * motor.ke_v_s_rad
        act.ctrllimited = 1
        act.ctrlrange = [-cfg.battery.v_full_v, cfg.battery.v_full_v]
        act.forcelimited = 1
        limit = motor.ke_v_s_rad * motor.current_limit_a
        act.forcerange = [-limit, limit]


def _add_casters(spec: mujoco.MjSpec, cfg: TwinConfig) -> None:
    k = cfg.caster
    for name in CASTERS:
        body = spec.body(f"caster_{name}_link")
        ball = _collision_geom(body)
        ball.name = f"caster_{name}_ball"
        # A frictionless ball: its rolling resistance (a force Crr * N against its
        # velocity) is applied by amr_twin.sim.rolling_resistance. Priority makes the
        # ball's friction, condim and solver parameters win the contact mix.
        ball.priority = 1
        ball.condim = 1
        ball.friction = [0.0, 0.0, 0.0]
        ball.solref, ball.solimp = list(CONTACT_SOLREF), list(CONTACT_SOLIMP)
        joint = spec.joint(f"caster_{name}_joint")
        joint.stiffness[0] = k.stiffness_n_m
        joint.damping[0] = k.damping_n_s_m
        joint.springref = -k.preload_n / k.stiffness_n_m  # preload against the lower stop
        joint.solref_limit = list(CONTACT_SOLREF)


def _add_payload(spec: mujoco.MjSpec, base: mujoco.MjsBody, cfg: TwinConfig) -> None:
    p = cfg.payload
    if p.mass_kg <= 0:
        return
    z = cfg.chassis.floor_c_z_m + cfg.chassis.sheet_thickness_m + p.size_m[2] / 2
    body = base.add_body(name="payload", pos=[p.xy_m[0], p.xy_m[1], z])
    body.add_geom(name="payload_box", type=mujoco.mjtGeom.mjGEOM_BOX, size=[s / 2 for s in p.size_m],
                  mass=p.mass_kg, group=GROUP_PAYLOAD, rgba=[0.80, 0.55, 0.25, 1.0],
                  contype=0, conaffinity=0)


def _add_sensors(spec: mujoco.MjSpec) -> None:
    # the first four sensor values are read every step by the loop: angle L, R, speed L, R
    for kind, suffix in ((mujoco.mjtSensor.mjSENS_JOINTPOS, "angle"), (mujoco.mjtSensor.mjSENS_JOINTVEL, "speed")):
        for side in WHEELS:
            spec.add_sensor(name=f"wheel_{side}_{suffix}", type=kind,
                            objtype=mujoco.mjtObj.mjOBJ_JOINT, objname=f"wheel_{side}_joint")
    # then the base pose (world): position (3) and orientation quaternion w, x, y, z (4)
    spec.add_sensor(name="base_pos", type=mujoco.mjtSensor.mjSENS_FRAMEPOS,
                    objtype=mujoco.mjtObj.mjOBJ_SITE, objname="base")
    spec.add_sensor(name="base_quat", type=mujoco.mjtSensor.mjSENS_FRAMEQUAT,
                    objtype=mujoco.mjtObj.mjOBJ_SITE, objname="base")
    for name, kind in (("imu_accel", mujoco.mjtSensor.mjSENS_ACCELEROMETER),
                       ("imu_gyro", mujoco.mjtSensor.mjSENS_GYRO),
                       ("imu_mag", mujoco.mjtSensor.mjSENS_MAGNETOMETER)):
        spec.add_sensor(name=name, type=kind, objtype=mujoco.mjtObj.mjOBJ_SITE, objname="imu")


def _world_spec(cfg: TwinConfig, world: str | Path) -> mujoco.MjSpec:
    path = Path(world)
    if not path.suffix:
        path = WORLD_DIR / f"{world}.xml"
    if not path.exists():
        names = sorted(p.stem for p in WORLD_DIR.glob("*.xml"))
        raise BuildError(f"--world {world}: no such world (available: {', '.join(names)})")
    if path.suffix in (".yaml", ".yml"):  # a ROS map_server map: walls extruded from the image
        from amr_twin.model.worlds import world_xml
        spec = mujoco.MjSpec.from_string(world_xml(path))
    else:
        try:
            spec = mujoco.MjSpec.from_file(str(path))
        except Exception as exc:  # XML parse errors name neither the file nor the problem's context
            first = " ".join(str(exc).split())[:200] or type(exc).__name__
            raise BuildError(f"--world {path}: not a valid MJCF world ({first})") from None
    spec.option.timestep = cfg.sim.timestep_s
    spec.option.integrator = mujoco.mjtIntegrator.mjINT_IMPLICITFAST
    spec.option.cone = mujoco.mjtCone.mjCONE_ELLIPTIC  # see _robot_spec
    spec.option.gravity = [0.0, 0.0, -cfg.sim.gravity_m_s2]
    spec.option.magnetic = [0.0, 2.2e-5, -4.3e-5]  # ~48 uT, northern-Italy inclination (WMM estimate)
    for geom in spec.geoms:
        geom.group = GROUP_WORLD
        if geom.type == mujoco.mjtGeom.mjGEOM_PLANE:
            geom.friction = [cfg.sim.floor_friction, 0.005, 0.0001]
    return spec


@dataclass
class Build:
    """Result of :func:`build`: the compiled model and the specs it came from."""

    model: mujoco.MjModel
    spec: mujoco.MjSpec
    robot_spec: mujoco.MjSpec
    urdf: str


def build(cfg: TwinConfig, world: str | Path = "warehouse", start_xy_yaw: tuple[float, float, float] = (0, 0, 0),
          xacro_file: Path = XACRO_FILE) -> Build:
    """Build the robot in a world and compile it (the URDF from :func:`robot_urdf`'s cache)."""
    urdf = robot_urdf(cfg, xacro_file)
    robot = _robot_spec(cfg, urdf)
    robot_xml = robot.to_xml()  # the robot alone, for export, before attaching
    scene = _world_spec(cfg, world)
    x, y, yaw = start_xy_yaw
    held = Path(world).stem == "stand"
    z = STAND_HEIGHT_M if held else 0.0
    frame = scene.worldbody.add_frame(pos=[x, y, z], quat=[math.cos(yaw / 2), 0, 0, math.sin(yaw / 2)])
    scene.attach(mujoco.MjSpec.from_string(robot_xml), prefix=ROBOT_PREFIX, frame=frame)
    if held:  # the work station of fig. 5.1: the chassis welded where it stands
        scene.add_equality(type=mujoco.mjtEq.mjEQ_WELD, objtype=mujoco.mjtObj.mjOBJ_BODY,
                           name1=ROBOT_PREFIX + "base_link", name="stand")
    try:
        model = scene.compile()
    except Exception as exc:
        raise BuildError(f"MuJoCo compile: {str(exc).splitlines()[0]}") from None
    return Build(model=model, spec=scene, robot_spec=robot, urdf=urdf)


def export(cfg: TwinConfig, urdf_path: Path | None = None, mjcf_path: Path | None = None) -> Build:
    """Write the URDF and the robot MJCF (the committed files are made this way)."""
    result = build(cfg)
    for path, text in ((urdf_path, result.urdf), (mjcf_path, result.robot_spec.to_xml())):
        if path is None:
            continue
        path = Path(path)
        tmp = path.with_suffix(path.suffix + ".tmp")
        tmp.write_text(text)
        tmp.replace(path)  # never leave a half-written file
    return result
