"""The robot's MjSpec: the URDF imported into MuJoCo plus everything URDF cannot carry.

On the MjSpec come the free joint, the wheel collision ellipsoids with the tyres' radial
springs, the caster springs (stiffness, damping, preload), contact parameters, the motor
actuators, sensor sites, the payload and the geom groups.

The first eleven sensor values are read by the loop every step
(:data:`LOOP_SENSOR_DIM`): wheel angles L, R; wheel speeds L, R; base position;
base quaternion.

Geom groups (``geomgroup`` masks): 0 world, 1 robot visuals, 2 robot collision,
4 payload. A LiDAR casts against groups 0 and 4 so that it never sees the robot's
own wheels and casters but does see a payload in its scan plane.
"""

from __future__ import annotations

import mujoco

from amr_twin.model import mass
from amr_twin.model.config import TwinConfig
from amr_twin.model.urdf import BuildError

GROUP_WORLD, GROUP_VISUAL, GROUP_COLLISION, GROUP_PAYLOAD = 0, 1, 2, 4
WHEELS = ("left", "right")
CASTERS = ("front_left", "front_right", "rear_left", "rear_right")
LOOP_SENSOR_DIM = 11
IMU_SENSORS = ("imu_accel", "imu_gyro", "imu_mag")
"""The IMU's MuJoCo sensors, after the loop's; :func:`amr_twin.model.build.build` can leave them
out."""


def robot_spec(cfg: TwinConfig, urdf: str, visuals: bool = True) -> mujoco.MjSpec:
    """The robot alone: URDF import plus everything URDF cannot carry.

    ``visuals=False``: without the URDF's visual elements (group 1), for a model nothing
    draws; they collide with nothing and weigh nothing (each link has its inertial).
    """
    # MuJoCo's URDF parser reads its options from a <mujoco> element in the URDF: keep the
    # visuals (it discards them by default, at parse time) and every link as a body.
    discard = "false" if visuals else "true"
    options = (
        f'<mujoco><compiler discardvisual="{discard}" fusestatic="false" '
        f'strippath="true"/></mujoco>'
    )
    spec = mujoco.MjSpec.from_string(urdf.replace("</robot>", options + "</robot>", 1))
    spec.compiler.discardvisual = (
        False  # at compile it would drop every contype-0 geom, the payload's too
    )
    spec.modelname = "amr"
    # Elliptic friction cones: the contact's first constraint row is its normal force
    # (read by Support.normal_forces_n); exported with the robot.
    spec.option.cone = mujoco.mjtCone.mjCONE_ELLIPTIC
    _tag_geoms(spec, cfg)
    base = spec.body("base_link")
    base.add_freejoint(name="root")
    _add_casters(spec, cfg)
    _add_wheels(spec, cfg)
    _add_payload(spec, base, cfg)
    imu = spec.body("imu_link")
    imu.add_site(
        name="imu", size=[0.01, 0.01, 0.002], type=mujoco.mjtGeom.mjGEOM_BOX, group=GROUP_VISUAL
    )
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
        tyre = body.add_joint(
            name=f"wheel_{side}_tyre", type=mujoco.mjtJoint.mjJNT_SLIDE, axis=[0, 0, 1]
        )
        tyre.stiffness[0] = w.tyre_stiffness_n_m
        tyre.damping[0] = w.tyre_damping_n_s_m
        tyre.springref = rotor_kg * g / w.tyre_stiffness_n_m
        joint = body.add_joint(
            name=f"wheel_{side}_joint", type=mujoco.mjtJoint.mjJNT_HINGE, axis=[0, 1, 0]
        )
        # The URDF effort limit would become a joint-level clamp of all actuator torque in
        # MuJoCo; the driver's current limit is the actuator's forcerange instead, so
        # that a shorted (braking) motor is limited by its own current, not the driver's.
        joint.actfrclimited = 0
        joint.damping[0] = motor.damping_nm_s_rad
        joint.frictionloss = motor.friction_nm
        kt_over_r = motor.ke_v_s_rad / motor.resistance_ohm  # Kt = Ke in SI units
        act = spec.add_actuator(
            name=f"motor_{side}", target=joint.name, trntype=mujoco.mjtTrn.mjTRN_JOINT
        )
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


def payload_centre_m(cfg: TwinConfig) -> tuple[float, float, float]:
    """Centre of the payload box in base_link, m: at ``payload.xy_m`` on floor (c)'s sheet."""
    p = cfg.payload
    z = cfg.chassis.floor_c_z_m + cfg.chassis.sheet_thickness_m + p.size_m[2] / 2
    return (p.xy_m[0], p.xy_m[1], z)


def _add_payload(spec: mujoco.MjSpec, base: mujoco.MjsBody, cfg: TwinConfig) -> None:
    p = cfg.payload
    if p.mass_kg <= 0:
        return
    body = base.add_body(name="payload", pos=list(payload_centre_m(cfg)))
    body.add_geom(
        name="payload_box",
        type=mujoco.mjtGeom.mjGEOM_BOX,
        size=[s / 2 for s in p.size_m],
        mass=p.mass_kg,
        group=GROUP_PAYLOAD,
        rgba=[0.80, 0.55, 0.25, 1.0],
        contype=0,
        conaffinity=0,
    )


def _add_sensors(spec: mujoco.MjSpec) -> None:
    # the first four sensor values are read every step by the loop: angle L, R, speed L, R
    for kind, suffix in (
        (mujoco.mjtSensor.mjSENS_JOINTPOS, "angle"),
        (mujoco.mjtSensor.mjSENS_JOINTVEL, "speed"),
    ):
        for side in WHEELS:
            spec.add_sensor(
                name=f"wheel_{side}_{suffix}",
                type=kind,
                objtype=mujoco.mjtObj.mjOBJ_JOINT,
                objname=f"wheel_{side}_joint",
            )
    # then the base pose (world): position (3) and orientation quaternion w, x, y, z (4)
    spec.add_sensor(
        name="base_pos",
        type=mujoco.mjtSensor.mjSENS_FRAMEPOS,
        objtype=mujoco.mjtObj.mjOBJ_SITE,
        objname="base",
    )
    spec.add_sensor(
        name="base_quat",
        type=mujoco.mjtSensor.mjSENS_FRAMEQUAT,
        objtype=mujoco.mjtObj.mjOBJ_SITE,
        objname="base",
    )
    for name, kind in zip(
        IMU_SENSORS,
        (
            mujoco.mjtSensor.mjSENS_ACCELEROMETER,
            mujoco.mjtSensor.mjSENS_GYRO,
            mujoco.mjtSensor.mjSENS_MAGNETOMETER,
        ),
    ):
        spec.add_sensor(name=name, type=kind, objtype=mujoco.mjtObj.mjOBJ_SITE, objname="imu")
