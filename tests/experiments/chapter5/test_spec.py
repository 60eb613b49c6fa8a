"""Chapter 5's spec checks its runs and duration from Python, without the CLI."""

import re

import pytest

from amr_twin.experiments.catalogue import experiments
from amr_twin.experiments.chapter5.spec import AttainableSpec, Chapter5Spec


def test_the_runs_named_and_their_simulated_time():
    assert Chapter5Spec().validate() is None and Chapter5Spec(runs="3,7").validate() == [3, 7]
    assert Chapter5Spec(runs="3,7").pass_s() == 32.0 and Chapter5Spec().pass_s() == 132.0
    assert Chapter5Spec().passes() == 2 and Chapter5Spec(runs="1").passes(4) == 5
    assert Chapter5Spec(runs="1", firmware="avr").passes() == 3


@pytest.mark.parametrize(
    "spec, named",
    [
        (Chapter5Spec(runs="1,x"), "--runs '1,x': expected run numbers 1..8 separated by commas"),
        (Chapter5Spec(runs="0,9"), "--runs '0,9': run numbers must lie in 1..8"),
        (Chapter5Spec(runs="2,2"), "--runs '2,2': a run is named twice"),
        (Chapter5Spec(duration_s=1e-9), "--duration-s 1e-09: must be in [0.1, 3600] s"),
    ],
)
def test_each_bad_field_is_refused_in_one_line_naming_it(spec, named):
    with pytest.raises(ValueError) as refused:
        spec.validate()
    assert str(refused.value).startswith(named) and "\n" not in str(refused.value)


def test_the_registry_holds_every_experiment_with_a_spec():
    assert experiments().get("chapter5").spec is Chapter5Spec
    assert set(experiments().names()) >= {"chapter5", "fusion", "payload", "umbmark"}


@pytest.mark.parametrize(
    "spec, named",
    [
        (AttainableSpec(samples=0), "--samples 0: must be in 1..512"),
        (AttainableSpec(samples=513), "--samples 513: must be in 1..512"),
        (AttainableSpec(seed=-1), "--seed -1: must be >= 0"),
    ],
)
def test_the_attainable_study_refuses_bad_draws_naming_the_field(spec, named):
    AttainableSpec().validate()
    with pytest.raises(ValueError, match=f"^{re.escape(named)}$"):
        spec.validate()
