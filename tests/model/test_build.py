"""Model build: xacro -> URDF -> MjSpec -> MJCF."""

import io
import subprocess
import sys

import numpy as np
import pytest
import yourdfpy

from amr_twin.model import build as build_mod
from amr_twin.model.build import GROUP_COLLISION, GROUP_PAYLOAD, GROUP_VISUAL, BuildError, build, urdf_string
from amr_twin.model.config import load_config
from amr_twin.model.mass import frame_members
from amr_twin.model.paths import MODEL_DIR


def test_committed_files_are_not_stale(tmp_path):
    """The committed URDF/MJCF equal what the build makes now (regenerate with amr-twin model --export-*)."""
    urdf, mjcf = tmp_path / "amr.urdf", tmp_path / "amr.xml"
    build_mod.export(load_config(), urdf, mjcf)
    assert (MODEL_DIR / "amr.urdf").read_text() == urdf.read_text(), \
        "models/amr/amr.urdf is stale: run amr-twin model --export-urdf models/amr/amr.urdf --export-mjcf models/amr/amr.xml"
    assert (MODEL_DIR / "amr.xml").read_text() == mjcf.read_text(), "models/amr/amr.xml is stale"


def test_urdf_is_valid_and_has_the_robot_structure():
    robot = yourdfpy.URDF.load(io.StringIO(urdf_string(load_config())), load_meshes=False)
    assert robot.validate()
    joints = {j.name: j for j in robot.robot.joints}
    assert joints["wheel_left_joint"].type == "continuous"
    assert joints["wheel_left_joint"].origin[1, 3] == pytest.approx(0.24)
    assert joints["wheel_right_joint"].origin[1, 3] == pytest.approx(-0.24)
    assert sum(j.type == "prismatic" for j in joints.values()) == 4
    assert {"laser", "imu_link", "uwb_tag"} <= {link.name for link in robot.robot.links}


def test_urdf_says_what_the_mjcf_has_as_far_as_urdf_can():
    """Every link has an inertial (no defaults for other tools to invent, e.g. PyBullet's 1 kg); wheel
    and caster joints carry the MJCF's damping, friction and limits in <dynamics> and <limit>."""
    import mujoco

    cfg = load_config()
    robot = yourdfpy.URDF.load(io.StringIO(urdf_string(cfg)), load_meshes=False)
    m = build(cfg, world="empty").model
    for link in robot.robot.links:
        assert link.inertial is not None and link.inertial.mass > 0, link.name
        body = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, "amr/" + link.name)
        assert m.body_mass[body] == pytest.approx(link.inertial.mass, rel=1e-6), link.name
    assert sum(link.inertial.mass for link in robot.robot.links) == pytest.approx(
        m.body_subtreemass[mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, "amr/base_link")], rel=1e-5)
    moving = [j for j in robot.robot.joints if j.type != "fixed"]
    assert len(moving) == 6
    for j in moving:
        k = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, "amr/" + j.name)
        assert j.dynamics is not None and j.limit is not None and float(j.limit.effort) > 0, j.name
        assert float(j.dynamics.damping) == pytest.approx(m.dof_damping[m.jnt_dofadr[k]]), j.name
        assert float(j.dynamics.friction) == pytest.approx(m.dof_frictionloss[m.jnt_dofadr[k]]), j.name
        if j.type == "prismatic":
            assert (float(j.limit.lower), float(j.limit.upper)) == pytest.approx(tuple(m.jnt_range[k]))
            assert float(j.limit.effort) == pytest.approx(cfg.caster.preload_n + cfg.caster.stiffness_n_m * cfg.caster.travel_m)
    left = robot.joint_map["wheel_left_joint"].dynamics
    assert (float(left.damping), float(left.friction)) == (cfg.motor_left.damping_nm_s_rad, cfg.motor_left.friction_nm)
    tag = robot.joint_map["uwb_tag_joint"]
    assert tuple(tag.origin[:3, 3]) == pytest.approx(cfg.uwb.tag_pos_m)


def test_urdf_frame_tubes_match_the_mass_model():
    """The xacro draws the same tubes whose mass mass.py computes."""
    cfg = load_config()
    robot = yourdfpy.URDF.load(io.StringIO(urdf_string(cfg)), load_meshes=False)
    base = robot.link_map["base_link"]
    t = cfg.chassis.tube_outer_m
    tubes = sorted(tuple(np.round(v.geometry.box.size, 6)) for v in base.visuals
                   if v.geometry.box is not None and min(v.geometry.box.size) == pytest.approx(t))
    expected = sorted(tuple(np.round(ext, 6)) for _, _, ext, _ in frame_members(cfg))
    assert tubes == expected


def test_broken_xacro_gives_one_line_error(tmp_path):
    bad = tmp_path / "bad.urdf.xacro"
    bad.write_text((MODEL_DIR / "amr.urdf.xacro").read_text().replace("p['wheel_width_m']", "p['no_such']"))
    with pytest.raises(BuildError) as info:
        build(load_config(), xacro_file=bad)
    assert "\n" not in str(info.value) and "xacro" in str(info.value)


def test_spec_adds_what_urdf_cannot_carry():
    cfg = load_config(sets=["payload.mass_kg=20"])
    m = build(cfg).model
    import mujoco
    names = lambda kind, n: [mujoco.mj_id2name(m, kind, i) for i in range(n)]
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


def test_unknown_world_is_refused():
    with pytest.raises(BuildError, match="no such world"):
        build(load_config(), world="moon")


def test_urdf_is_made_and_checked_once_per_robot(monkeypatch, tmp_path):
    """robot_urdf: xacro and yourdfpy run once per fingerprint; the payload (added on the MjSpec)
    does not change it, a wheel radius does; a fresh process reads the disk cache."""
    monkeypatch.setenv("AMR_TWIN_CACHE_DIR", str(tmp_path))
    monkeypatch.setattr(build_mod, "_urdf_memo", {})
    calls = []
    real_check = build_mod.check_urdf
    monkeypatch.setattr(build_mod, "check_urdf", lambda urdf: (calls.append(1), real_check(urdf)))
    base = load_config()
    first = build_mod.robot_urdf(base)
    assert first == urdf_string(base) and len(calls) == 1
    assert build_mod.robot_urdf(load_config(sets=["payload.mass_kg=30"])) == first and len(calls) == 1
    bigger = load_config(sets=["wheel.radius_m=0.13"])
    assert build_mod.urdf_fingerprint(bigger) != build_mod.urdf_fingerprint(base)
    assert build_mod.robot_urdf(bigger) == urdf_string(bigger) and len(calls) == 2
    assert len(list((tmp_path / "urdf").glob("*.urdf"))) == 2
    code = ("import amr_twin.model.build as b, sys; from amr_twin.model.config import load_config; "
            "b.urdf_string = None; b.robot_urdf(load_config()); print('xacro' in sys.modules)")
    env = {**__import__("os").environ, "AMR_TWIN_CACHE_DIR": str(tmp_path)}
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env, check=True)
    assert out.stdout.strip() == "False"  # from the disk: neither xacro nor yourdfpy


def test_unwritable_urdf_cache_still_builds(monkeypatch, tmp_path):
    blocker = tmp_path / "not_a_folder"
    blocker.write_text("")
    monkeypatch.setenv("AMR_TWIN_CACHE_DIR", str(blocker))
    monkeypatch.setattr(build_mod, "_urdf_memo", {})
    assert build(load_config(), world="empty").model.nu == 2
    monkeypatch.setenv("AMR_TWIN_CACHE_DIR", "")
    assert build_mod.urdf_cache_dir() is None
