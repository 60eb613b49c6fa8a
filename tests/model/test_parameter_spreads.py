"""Each parameter's spread: the leaf keys (checked, one line), defaults by source kind, settings
never drawn, the calibrated parameters from the calibration's report (no mujoco)."""

import pytest
import yaml

from amr_twin.model.config import ConfigError, load_parameters
from amr_twin.model.parameter_tree import DEFAULT_CONFIG
from amr_twin.model.parameter_spreads import (
    CALIBRATED,
    EXACT,
    FOLLOWS,
    NORMAL,
    UNIFORM,
    source_kind,
)
from amr_twin.calibration.uncertainty import ParameterSpace


@pytest.fixture(scope="module")
def space():
    return ParameterSpace.load()


def _file_with(tmp_path, section, key, **leaf):
    tree = yaml.safe_load(DEFAULT_CONFIG.read_text())
    tree[section][key].update(leaf)
    path = tmp_path / "amr.yaml"
    path.write_text(yaml.safe_dump(tree))
    return path


@pytest.mark.parametrize(
    "leaf, words",
    [
        (
            {"range": [0.06, 0.07], "reason": "r"},
            "wheel.width_m: value 0.05 lies outside its range",
        ),
        (
            {"range": [0.005, 0.06], "reason": "r"},
            "wheel.width_m: range [0.005, 0.06] leaves the allowed [0.01, 0.15] m",
        ),
        ({"range": [0.04, 0.06]}, "wheel.width_m: range needs its reason"),
        ({"sigma": -0.001, "reason": "r"}, "wheel.width_m: sigma must be finite and >= 0"),
        (
            {"sigma": 0.001, "range": [0.04, 0.06], "reason": "r"},
            "give one of range, sigma or follows",
        ),
        ({"follows": "wheel.nothing", "reason": "r"}, "wheel.width_m: follows 'wheel.nothing'"),
        ({"reason": "why"}, "wheel.width_m: reason without range, sigma or follows"),
        ({"spread": 3}, "wheel.width_m: unknown leaf key(s) ['spread']"),
    ],
)
def test_bad_spread_keys_are_refused_in_one_line(tmp_path, leaf, words):
    with pytest.raises(ConfigError) as info:
        load_parameters(_file_with(tmp_path, "wheel", "width_m", **leaf))
    assert words in str(info.value) and "\n" not in str(info.value)


def test_leaf_spreads_and_overrides_are_described(tmp_path):
    mine = tmp_path / "mine.yaml"
    mine.write_text(
        yaml.safe_dump(
            {
                "caster": {"preload_n": {"value": 25.0, "range": [20.0, 30.0], "reason": "mine"}},
                "wheel": {"mass_kg": 3.2},
            }
        )
    )
    cfg, meta = load_parameters(override_file=mine, sets=["caster.stiffness_n_m=21000"])
    assert cfg.caster.preload_n == 25.0
    assert (
        meta["caster.preload_n"]["range"] == [20.0, 30.0]
        and "set_by" not in meta["caster.preload_n"]
    )
    assert (
        meta["wheel.mass_kg"]["set_by"].startswith("--params")
        and "range" not in meta["wheel.mass_kg"]
    )
    assert meta["caster.stiffness_n_m"]["set_by"] == "--set"
    space = ParameterSpace.load(override_file=mine, sets=["caster.stiffness_n_m=21000"])
    assert (space.spreads["caster.preload_n"].low, space.spreads["caster.preload_n"].high) == (
        20.0,
        30.0,
    )
    assert space.spreads["wheel.mass_kg"].kind == EXACT  # the user chose it
    assert space.spreads["caster.stiffness_n_m"].kind == EXACT


def test_source_kinds():
    assert source_kind("calibrated: amr-twin calibrate") == "calibrated"
    assert source_kind("datasheet: RPLIDAR") == "datasheet"
    assert source_kind("thesis §2.2.1") == "thesis"
    assert source_kind("estimate from datasheet: ...") == "estimate"
    assert source_kind("robot-facts.md decision: 30 mm") == "estimate"
    assert source_kind("standard gravity") == "other"


def test_defaults_follow_the_source_kind(space):
    s = space.spreads
    assert (
        s["caster.damping_n_s_m"].kind,
        s["caster.damping_n_s_m"].low,
        s["caster.damping_n_s_m"].high,
    ) == (UNIFORM, pytest.approx(240.0), pytest.approx(360.0))  # estimate +-20 %
    assert (s["components.lidar.mass_kg"].low, s["components.lidar.mass_kg"].high) == (
        pytest.approx(0.1615),
        pytest.approx(0.1785),
    )  # datasheet +-5 %
    assert (s["battery.capacity_ah"].low, s["battery.capacity_ah"].high) == (
        pytest.approx(19.6),
        pytest.approx(20.4),
    )
    assert (
        s["sim.gravity_m_s2"].kind == EXACT and s["driver.deadband_duty"].kind == EXACT
    )  # standard; zero
    assert s["components.charger.pos_m"].kind == EXACT  # a vector without sigma
    assert s["components.battery.pos_m"].kind == NORMAL and s["components.battery.pos_m"].sigma == (
        0.03,
        0.01,
        0.0,
    )
    assert (
        s["wheel.friction"].kind == FOLLOWS and s["wheel.friction"].follows == "sim.floor_friction"
    )
    assert (s["caster.drop_m"].low, s["caster.drop_m"].high) == (-0.002, 0.002)  # the leaf's range


def test_settings_are_never_drawn(space):
    for key in (
        "sim.timestep_s",
        "payload.mass_kg",
        "ekf.accel_sigma_m_s2",
        "lidar.sample_rate_hz",
        "mapping.resolution_m",
        "uwb.anchors_x_m",
        "navigation.mppi.step_s",
    ):
        assert space.spreads[key].kind == EXACT and not space.spreads[key].drawn, key
    assert not [
        k for k in space.drawn_keys() if k.startswith(("navigation.", "actors."))
    ]  # ranges or not
    drawn = space.draw(8, include=("sim.", "payload.", "ekf.", "mapping.")).names
    assert drawn == (
        "sim.floor_friction",
        "sim.floor_friction_low",
        "sim.floor_patch_m",
    )  # the floor's, all physical


def test_calibrated_parameters_come_from_the_report(space):
    rep = space.calibration
    for key in ("driver_left.gain", "motor_left.ke_v_s_rad", "motor_right.friction_nm"):
        assert space.spreads[key].kind == CALIBRATED
        assert space.spreads[key].sigma == (pytest.approx(float(rep.sigma[rep.keys.index(key)])),)
    assert (
        rep.correlation[rep.keys.index("driver_left.gain"), rep.keys.index("motor_left.ke_v_s_rad")]
        > 0.95
    )


def test_a_calibrated_value_the_report_does_not_describe_is_refused(tmp_path):
    mine = tmp_path / "mine.yaml"
    mine.write_text(
        yaml.safe_dump(
            {"driver_left": {"gain": {"value": 1.9, "source": "calibrated: my own log"}}}
        )
    )
    with pytest.raises(
        ConfigError, match=r"driver_left.gain: 1.9 here but 1.698 in the calibration report"
    ):
        ParameterSpace.load(override_file=mine)
    with pytest.raises(ConfigError, match="no such|cannot read"):
        ParameterSpace.load(calibration=tmp_path / "missing.yaml")
