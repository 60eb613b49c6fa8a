"""The robot's MjSpec: what URDF cannot carry, added on the imported URDF."""

import io

import pytest
import yourdfpy

from amr_twin.model.build import build
from amr_twin.model.config import load_config
from amr_twin.model.robot_spec import GROUP_COLLISION, GROUP_PAYLOAD, GROUP_VISUAL
from amr_twin.model.urdf import urdf_string


def test_urdf_says_what_the_mjcf_has_as_far_as_urdf_can():
    """Every link has an inertial (no defaults for other tools to invent, e.g. PyBullet's 1 kg);
    wheel and caster joints carry the MJCF's damping, friction and limits in <dynamics> and
    <limit>."""
    import mujoco

    cfg = load_config()
    robot = yourdfpy.URDF.load(io.StringIO(urdf_string(cfg)), load_meshes=False)
    m = build(cfg, world="empty").model
    for link in robot.robot.links:
        assert link.inertial is not None and link.inertial.mass > 0, link.name
        body = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, "amr/" + link.name)
        assert m.body_mass[body] == pytest.approx(link.inertial.mass, rel=1e-6), link.name
    assert sum(link.inertial.mass for link in robot.robot.links) == pytest.approx(
        m.body_subtreemass[mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, "amr/base_link")],
        rel=1e-5,
    )
    moving = [j for j in robot.robot.joints if j.type != "fixed"]
    assert len(moving) == 6
    for j in moving:
        k = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, "amr/" + j.name)
        assert j.dynamics is not None and j.limit is not None and float(j.limit.effort) > 0, j.name
        assert float(j.dynamics.damping) == pytest.approx(m.dof_damping[m.jnt_dofadr[k]]), j.name
        assert float(j.dynamics.friction) == pytest.approx(m.dof_frictionloss[m.jnt_dofadr[k]]), (
            j.name
        )
        if j.type == "prismatic":
            assert (float(j.limit.lower), float(j.limit.upper)) == pytest.approx(
                tuple(m.jnt_range[k])
            )
            assert float(j.limit.effort) == pytest.approx(
                cfg.caster.preload_n + cfg.caster.stiffness_n_m * cfg.caster.travel_m
            )
    left = robot.joint_map["wheel_left_joint"].dynamics
    assert (float(left.damping), float(left.friction)) == (
        cfg.motor_left.damping_nm_s_rad,
        cfg.motor_left.friction_nm,
    )
    tag = robot.joint_map["uwb_tag_joint"]
    assert tuple(tag.origin[:3, 3]) == pytest.approx(cfg.uwb.tag_pos_m)


def test_spec_adds_what_urdf_cannot_carry():
    cfg = load_config(sets=["payload.mass_kg=20"])
    m = build(cfg).model
    import mujoco

    def names(kind, n):
        return [mujoco.mj_id2name(m, kind, i) for i in range(n)]

    assert m.jnt_type[0] == mujoco.mjtJoint.mjJNT_FREE
    assert names(mujoco.mjtObj.mjOBJ_ACTUATOR, m.nu) == ["amr/motor_left", "amr/motor_right"]
    casters = [i for i, n in enumerate(names(mujoco.mjtObj.mjOBJ_JOINT, m.njnt)) if "caster" in n]
    assert all(m.jnt_stiffness[i] == cfg.caster.stiffness_n_m for i in casters)
    assert all(m.qpos_spring[m.jnt_qposadr[i]] < 0 for i in casters)  # preload
    ball = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_GEOM, "amr/caster_front_left_ball")
    assert m.geom_priority[ball] >= 1 and m.geom_condim[ball] == 1
    wheel = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_GEOM, "amr/wheel_left_collision")
    assert m.geom_type[wheel] == mujoco.mjtGeom.mjGEOM_ELLIPSOID
    payload = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_GEOM, "amr/payload_box")
    assert m.geom_group[payload] == GROUP_PAYLOAD
    robot_geoms = m.geom_bodyid > 0
    assert set(m.geom_group[robot_geoms]) <= {GROUP_VISUAL, GROUP_COLLISION, GROUP_PAYLOAD}
    base = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, "amr/base_link")
    assert m.body_subtreemass[base] == pytest.approx(30.35 + 20, abs=0.05)
