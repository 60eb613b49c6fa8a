"""The payload sweep's spec checks its inputs from Python, without the CLI, as the CLI does."""

import math

import pytest

from amr_twin.experiments.catalogue import experiments
from amr_twin.experiments.payload.spec import MAX_SWEEP_POINTS, PayloadSweepSpec
from amr_twin.model.config import load_config


@pytest.fixture(scope="module")
def cfg():
    return load_config()


def test_the_default_sweep_is_valid_and_its_grid_counted(cfg):
    grid = PayloadSweepSpec().validate(cfg)
    assert (len(grid.masses), len(grid.positions), len(grid.commands)) == (13, 5, 2)
    assert grid.points == 130 and grid.repeated == []


def test_a_sweep_over_the_most_runs_is_refused_naming_its_fields(cfg):
    one = {"positions": "center", "commands": "linear:0.7", "samples": 100}
    spec = PayloadSweepSpec(masses="0:99:1", **one)
    with pytest.raises(ValueError) as refused:
        spec.validate(cfg)
    assert str(refused.value).startswith(
        "--masses x --positions x --commands x (--samples + 1): "
        f"10100 runs; at most {MAX_SWEEP_POINTS} per sweep"
    )
    assert "\n" not in str(refused.value)
    PayloadSweepSpec(masses="0:98:1", **one).validate(cfg)  # 9999 runs


@pytest.mark.parametrize(
    "field, value, named",
    [
        ("duration_s", math.nan, "--duration-s nan: must be a finite number"),
        ("duration_s", 7200.0, "--duration-s 7200: must be in"),
        ("masses", "0:60:0", "--masses '0:60:0'"),
        ("positions", "5:5", "--positions '5:5': the payload box"),
        ("commands", "spin:3", "--commands"),
        ("positions", " , ", "--positions and --commands must name at least one item each"),
    ],
)
def test_each_bad_field_is_refused_in_one_line_naming_it(cfg, field, value, named):
    with pytest.raises(ValueError) as refused:
        PayloadSweepSpec(**{field: value}).validate(cfg)
    assert str(refused.value).startswith(named) and "\n" not in str(refused.value)


def test_repeated_values_are_kept_once(cfg):
    spec = PayloadSweepSpec(masses="10,10.0,20", positions="center,0:0", commands="linear:0.7")
    grid = spec.validate(cfg)
    assert grid.masses == [10.0, 20.0] and grid.positions == ["center"]
    assert grid.repeated == [10.0, "0:0"]


def test_the_registry_names_the_sweep_and_refuses_an_unknown_experiment():
    entry = experiments().get("payload")
    assert entry.spec is PayloadSweepSpec and entry.name == "payload"
    with pytest.raises(ValueError, match="^experiment 'nope': must be one of .*payload"):
        experiments().get("nope")
