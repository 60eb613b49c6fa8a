"""Parameter file: validation, overrides, one-line errors (no mujoco)."""

import math

import pytest
import yaml

from amr_twin.model.config import ConfigError, load_config, parameter_table
from amr_twin.model.parameter_tree import DEFAULT_CONFIG


def test_every_parameter_has_unit_and_source():
    rows = parameter_table()
    assert len(rows) > 50
    for key, _value, unit, source in rows:
        assert unit, key
        assert len(source) > 8, f"{key}: source too short"
        assert any(
            w in source
            for w in (
                "thesis",
                "estimate",
                "datasheet",
                "calibrated",
                "robot-facts",
                "set per run",
                "standard",
                "nav2",
                "measured",
                "acceptance",
            )
        ), key


def test_thesis_geometry_loaded():
    cfg = load_config()
    assert cfg.wheel.radius_m == 0.125
    assert cfg.wheel.separation_m == 0.48
    assert cfg.caster.ball_diameter_m == 0.030


def test_config_is_frozen():
    cfg = load_config()
    with pytest.raises(Exception):
        cfg.wheel.radius_m = 0.2


@pytest.mark.parametrize(
    "assignment, field, words",
    [
        ("payload.mass_kg=-1", "payload.mass_kg", "[0.0, 200.0]"),
        ("wheel.foo=1", "wheel.foo", "is not a parameter"),
        ("wheel.radius_m=.nan", "wheel.radius_m", "finite"),
        ("chassis.width_m=0.9", "chassis.width_m", "[0.25, 0.46]"),
        ("payload.xy_m=[0.3,0.0]", "payload.xy_m", "outside the deck"),
        ("navigation.mppi.samples=5", "navigation.mppi.samples", "16"),
        (
            "navigation.costmap.raytrace_range_m=2",
            "navigation.costmap.raytrace_range_m",
            "obstacle_range_m",
        ),
    ],
)
def test_bad_values_give_one_line_naming_the_option_and_the_field(assignment, field, words):
    sets = [assignment]
    if assignment.startswith("payload.xy"):
        sets.insert(0, "payload.mass_kg=20")
    with pytest.raises(ConfigError) as info:
        load_config(sets=sets)
    message = str(info.value)
    assert "\n" not in message
    assert message.startswith(f"--set {assignment!r}: ") and field in message
    assert words in message


def test_override_file_and_set(tmp_path):
    extra = tmp_path / "mine.yaml"
    extra.write_text(
        yaml.safe_dump({"payload": {"mass_kg": 12.5}, "wheel": {"radius_m": {"value": 0.13}}})
    )
    cfg = load_config(override_file=extra, sets=["payload.xy_m=[0.05,0.0]"])
    assert cfg.payload.mass_kg == 12.5
    assert cfg.wheel.radius_m == 0.13
    assert cfg.payload.xy_m == (0.05, 0.0)


def test_unit_mismatch_is_refused(tmp_path):
    tree = yaml.safe_load(DEFAULT_CONFIG.read_text())
    tree["wheel"]["radius_m"]["unit"] = "mm"
    bad = tmp_path / "bad.yaml"
    bad.write_text(yaml.safe_dump(tree))
    with pytest.raises(ConfigError, match=r"wheel.radius_m: unit 'mm'"):
        load_config(bad)


def test_unknown_section_in_file(tmp_path):
    tree = yaml.safe_load(DEFAULT_CONFIG.read_text())
    tree["warp_drive"] = {"value": 1, "unit": "1", "source": "estimate"}
    bad = tmp_path / "bad.yaml"
    bad.write_text(yaml.safe_dump(tree))
    with pytest.raises(ConfigError, match="warp_drive: unknown key"):
        load_config(bad)


def test_battery_voltages_must_be_ordered():
    with pytest.raises(ConfigError, match="battery"):
        load_config(sets=["battery.v_full_v=35"])
    assert math.isfinite(load_config().battery.v_full_v)


def test_model_readme_lists_every_parameter():
    from amr_twin.model.paths import MODEL_DIR

    readme = (MODEL_DIR / "README.md").read_text()
    missing = [key for key, *_ in parameter_table() if f"`{key}`" not in readme]
    assert not missing, f"models/amr/README.md lacks {missing}"


def test_model_readme_is_current():
    from amr_twin.calibration.parameter_doc import readme_text
    from amr_twin.model.paths import MODEL_DIR

    assert (MODEL_DIR / "README.md").read_text() == readme_text(), (
        "models/amr/README.md is stale: run python -m amr_twin.calibration.parameter_doc"
    )


def test_a_parameter_file_that_is_a_folder_or_binary_is_named(tmp_path):
    from typer.testing import CliRunner

    from amr_twin.cli.main import app

    binary = tmp_path / "p.yaml"
    binary.write_bytes(bytes(range(128, 256)) * 8)
    for path, text in ((tmp_path, "is a folder"), (binary, "not a text file")):
        with pytest.raises(ConfigError, match=text):
            load_config(override_file=path)
        res = CliRunner().invoke(app, ["model", "--params", str(path)])
        assert res.exit_code == 2 and res.stderr.startswith(f"error: --params {path}: ")
        assert len(res.stderr.strip().splitlines()) == 1
    (tmp_path / "o.yaml").write_text("wheel:\n  radiuss_m: 3\n")
    with pytest.raises(ConfigError, match=r"o.yaml: wheel.radiuss_m: unknown key"):
        load_config(override_file=tmp_path / "o.yaml")


def test_with_values_replaces_and_validates_like_a_loaded_file():
    """with_values (a sweep point's payload) gives what loading the file with the same overrides
    gives, and refuses what loading refuses, with the same one-line messages."""
    from amr_twin.model.config import with_values

    base = load_config(overrides={"wheel.radius_m": 0.081})
    changes = {"payload.mass_kg": 30.0, "payload.xy_m": [-0.1, 0.05]}
    assert with_values(base, changes) == load_config(overrides={"wheel.radius_m": 0.081, **changes})
    assert with_values(base, changes).wheel.radius_m == 0.081
    for bad, message in (
        ({"payload.mass_kg": -1.0}, "payload.mass_kg: -1.0 is out of range"),
        ({"payload.mass_kg": float("nan")}, "payload.mass_kg: nan must be a finite number"),
        ({"payload.colour": 1}, "payload.colour: unknown key"),
        ({"payload.mass_kg": 5.0, "payload.xy_m": [0.5, 0.0]}, "outside the deck"),
    ):
        with pytest.raises(ConfigError, match=message.replace(".", r"\.")) as info:
            with_values(base, bad)
        with pytest.raises(ConfigError) as loaded:
            load_config(overrides={"wheel.radius_m": 0.081, **bad})
        assert str(info.value) == str(loaded.value) and "\n" not in str(info.value)
