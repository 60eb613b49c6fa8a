"""Model build: the robot in a world, compiled, and the committed URDF/MJCF it exports."""

import pytest

from amr_twin.model import build as build_mod
from amr_twin.model.build import BuildError, build
from amr_twin.model.config import load_config
from amr_twin.model.paths import MODEL_DIR


def test_committed_files_are_not_stale(tmp_path):
    """The committed URDF/MJCF equal what the build makes now (regenerate with amr-twin model --export-*)."""
    urdf, mjcf = tmp_path / "amr.urdf", tmp_path / "amr.xml"
    build_mod.export(load_config(), urdf, mjcf)
    assert (MODEL_DIR / "amr.urdf").read_text() == urdf.read_text(), \
        "models/amr/amr.urdf is stale: run amr-twin model --export-urdf models/amr/amr.urdf --export-mjcf models/amr/amr.xml"
    assert (MODEL_DIR / "amr.xml").read_text() == mjcf.read_text(), "models/amr/amr.xml is stale"


def test_broken_xacro_gives_one_line_error(tmp_path):
    bad = tmp_path / "bad.urdf.xacro"
    bad.write_text((MODEL_DIR / "amr.urdf.xacro").read_text().replace("p['wheel_width_m']", "p['no_such']"))
    with pytest.raises(BuildError) as info:
        build(load_config(), xacro_file=bad)
    assert "\n" not in str(info.value) and "xacro" in str(info.value)


def test_unknown_world_is_refused():
    with pytest.raises(BuildError, match="no such world"):
        build(load_config(), world="moon")


def test_a_model_without_visuals_or_imu_weighs_the_same():
    """build(visuals=False, imu=False): no robot visual geom, no IMU sensor; the same masses and
    inertias, collision shapes, payload box (the LiDAR sees it) and loop sensors."""
    import numpy as np

    from amr_twin.model.robot_spec import GROUP_COLLISION, GROUP_PAYLOAD, GROUP_VISUAL, IMU_SENSORS, LOOP_SENSOR_DIM

    cfg = load_config(overrides={"payload.mass_kg": 25.0})
    full = build(cfg, world="empty")
    lean = build(cfg, world="empty", visuals=False, imu=False)
    a, b = full.model, lean.model
    assert sum(a.geom_group == GROUP_VISUAL) >= 30 and GROUP_VISUAL not in b.geom_group
    assert sum(a.geom_group == GROUP_COLLISION) == sum(b.geom_group == GROUP_COLLISION) >= 9
    assert sum(a.geom_group == GROUP_PAYLOAD) == sum(b.geom_group == GROUP_PAYLOAD) == 1
    for name in ("body_mass", "body_inertia", "body_ipos", "body_iquat", "body_subtreemass", "jnt_stiffness"):
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name), err_msg=name)
    assert a.body_subtreemass[1] > 25.0
    assert a.nsensordata == b.nsensordata + 9 and b.nsensordata == LOOP_SENSOR_DIM
    assert {lean.spec.sensor("amr/" + n) for n in IMU_SENSORS} == {None}


def test_the_viewer_scene_has_the_twins_options():
    """models/amr/scene.xml (for MuJoCo's viewer) loads and steps with the options the twin builds with."""
    import mujoco

    viewer = mujoco.MjModel.from_xml_path(str(MODEL_DIR / "scene.xml")).opt
    twin = build(load_config()).model.opt
    for name in ("timestep", "integrator", "cone", "disableflags", "enableflags"):
        assert getattr(viewer, name) == getattr(twin, name), name
