"""Model build: the robot in a world, compiled, and the committed URDF/MJCF it exports."""

import re

import numpy as np
import pytest

from amr_twin.model import build as build_mod
from amr_twin.model.build import BuildError, build
from amr_twin.model.config import load_config
from amr_twin.model.paths import MODEL_DIR


NUMBER = re.compile(r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?")


def _numbers_and_text(text: str) -> tuple[list[float], str]:
    """The numbers of an XML text, and the text with each number replaced by ``#``."""
    return [float(v) for v in NUMBER.findall(text)], NUMBER.sub("#", text)


def _assert_same_model(committed: str, fresh: str, name: str) -> None:
    """Same structure and names to the character, every number within 1e-9 relative (1e-12
    absolute): a float's last printed digit moves with numpy's and libm's versions, a parameter
    change does not hide in it (the smallest one the parameter file can express moves an inertia by
    ~1e-6)."""
    a_num, a_text = _numbers_and_text(committed)
    b_num, b_text = _numbers_and_text(fresh)
    assert a_text == b_text, f"models/amr/{name} is stale (its structure): {REGENERATE}"
    assert len(a_num) == len(b_num)
    np.testing.assert_allclose(
        a_num, b_num, rtol=1e-9, atol=1e-12, err_msg=f"models/amr/{name} is stale: {REGENERATE}"
    )


REGENERATE = "run amr-twin model --export-urdf models/amr/amr.urdf --export-mjcf models/amr/amr.xml"


def test_committed_files_are_not_stale(tmp_path):
    """The committed URDF/MJCF equal what the build makes now, to the last digit that does not
    depend on the machine (regenerate with amr-twin model --export-*)."""
    urdf, mjcf = tmp_path / "amr.urdf", tmp_path / "amr.xml"
    build_mod.export(load_config(), urdf, mjcf)
    _assert_same_model((MODEL_DIR / "amr.urdf").read_text(), urdf.read_text(), "amr.urdf")
    _assert_same_model((MODEL_DIR / "amr.xml").read_text(), mjcf.read_text(), "amr.xml")


def test_the_staleness_check_sees_a_parameter_change(tmp_path):
    """A wheel 1 g heavier (the last digit the parameter file gives a mass) fails the check; a
    last-digit wobble of a printed float does not."""
    urdf, mjcf = tmp_path / "amr.urdf", tmp_path / "amr.xml"
    build_mod.export(load_config(overrides={"wheel.mass_kg": 3.501}), urdf, mjcf)
    with pytest.raises(AssertionError, match="stale"):
        _assert_same_model((MODEL_DIR / "amr.urdf").read_text(), urdf.read_text(), "amr.urdf")
    committed = (MODEL_DIR / "amr.urdf").read_text()
    value = NUMBER.findall(committed.split("ixx=")[1])[0]
    wobbled = committed.replace(value, value[:-1] + str((int(value[-1]) + 1) % 10), 1)
    _assert_same_model(committed, wobbled, "amr.urdf")


def test_broken_xacro_gives_one_line_error(tmp_path):
    bad = tmp_path / "bad.urdf.xacro"
    bad.write_text(
        (MODEL_DIR / "amr.urdf.xacro").read_text().replace("p['wheel_width_m']", "p['no_such']")
    )
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

    from amr_twin.model.robot_spec import (
        GROUP_COLLISION,
        GROUP_PAYLOAD,
        GROUP_VISUAL,
        IMU_SENSORS,
        LOOP_SENSOR_DIM,
    )

    cfg = load_config(overrides={"payload.mass_kg": 25.0})
    full = build(cfg, world="empty")
    lean = build(cfg, world="empty", visuals=False, imu=False)
    a, b = full.model, lean.model
    assert sum(a.geom_group == GROUP_VISUAL) >= 30 and GROUP_VISUAL not in b.geom_group
    assert sum(a.geom_group == GROUP_COLLISION) == sum(b.geom_group == GROUP_COLLISION) >= 9
    assert sum(a.geom_group == GROUP_PAYLOAD) == sum(b.geom_group == GROUP_PAYLOAD) == 1
    for name in (
        "body_mass",
        "body_inertia",
        "body_ipos",
        "body_iquat",
        "body_subtreemass",
        "jnt_stiffness",
    ):
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name), err_msg=name)
    assert a.body_subtreemass[1] > 25.0
    assert a.nsensordata == b.nsensordata + 9 and b.nsensordata == LOOP_SENSOR_DIM
    assert {lean.spec.sensor("amr/" + n) for n in IMU_SENSORS} == {None}


def test_the_viewer_scene_has_the_twins_options():
    """models/amr/scene.xml (for MuJoCo's viewer) loads and steps with the options the twin builds
    with."""
    import mujoco

    viewer = mujoco.MjModel.from_xml_path(str(MODEL_DIR / "scene.xml")).opt
    twin = build(load_config()).model.opt
    for name in ("timestep", "integrator", "cone", "disableflags", "enableflags"):
        assert getattr(viewer, name) == getattr(twin, name), name


def test_the_exported_mjcf_has_the_twins_options(tmp_path):
    """The robot MJCF, fresh and committed, loaded alone carries every mjOption field the twin's
    model runs with (timestep, integrator, cone, solver, iterations, noslip, flags, gravity,
    magnetic)."""
    import mujoco

    from amr_twin.model.build import _option_fields

    mjcf = tmp_path / "amr.xml"
    twin = build_mod.export(load_config(), mjcf_path=mjcf).model.opt
    assert (
        twin.timestep == load_config().sim.timestep_s
    )  # no tyre halving at the default parameters
    for path in (mjcf, MODEL_DIR / "amr.xml"):
        exported = mujoco.MjModel.from_xml_path(str(path)).opt
        for name in _option_fields(twin):
            np.testing.assert_array_equal(
                getattr(exported, name), getattr(twin, name), err_msg=f"{path.name}: {name}"
            )
