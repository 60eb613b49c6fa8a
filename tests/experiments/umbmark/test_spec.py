"""UMBmark's spec checks its inputs from Python, without the CLI, in one line naming the field."""

import pytest

from amr_twin.experiments.catalogue import experiments
from amr_twin.experiments.umbmark.seeds import MAX_RUNS
from amr_twin.experiments.umbmark.spec import UmbmarkSpec


def test_the_default_spec_names_ten_robots_and_its_squares():
    spec = UmbmarkSpec()
    assert spec.validate() == list(range(10))
    assert spec.squares(10) == 10 * 5 * 2 * 3
    assert UmbmarkSpec(tyres=False).squares(10) == 10 * 5 * 2 * 2
    assert spec.values() == {"wheel.tyre_slip": True, "sim.floor_friction_field": True}


@pytest.mark.parametrize(
    "spec, sets, named",
    [
        (UmbmarkSpec(seeds="3:1"), [], "--seeds '3:1': names no seed"),
        (UmbmarkSpec(runs=0), [], f"--runs 0: must be in 1..{MAX_RUNS}"),
        (UmbmarkSpec(runs=MAX_RUNS + 1), [], f"--runs {MAX_RUNS + 1}: must be in 1..{MAX_RUNS}"),
        (
            UmbmarkSpec(),
            ["wheel.tyre_slip=false"],
            "--set wheel.tyre_slip: chosen by this command's --tyres",
        ),
    ],
)
def test_each_bad_field_is_refused_in_one_line_naming_it(spec, sets, named):
    with pytest.raises(ValueError) as refused:
        spec.validate(sets)
    assert str(refused.value).startswith(named) and "\n" not in str(refused.value)


def test_a_parameter_file_may_not_choose_the_contact(tmp_path):
    params = tmp_path / "p.yaml"
    params.write_text("sim:\n  floor_friction_field: false\n")
    chosen = r"^--params .*p.yaml: sim.floor_friction_field is chosen by"
    with pytest.raises(ValueError, match=chosen):
        UmbmarkSpec().validate([], params)
    params.write_text("sim:\n  timestep_s: 0.001\n")
    assert UmbmarkSpec(seeds="4").validate([], params) == [4]


def test_the_registry_holds_umbmark_with_its_spec():
    assert experiments().get("umbmark").spec is UmbmarkSpec
    assert {"payload", "umbmark"} <= set(experiments().names())
