"""A third party adds an experiment from its own module, and finds it beside the built-ins."""

from dataclasses import dataclass

import pytest

from amr_twin.experiments.catalogue import experiments
from amr_twin.experiments.registry import EXPERIMENTS, Experiment


@dataclass(frozen=True)
class _DriftSpec:
    laps: int = 1

    def validate(self) -> None:
        if self.laps < 1:
            raise ValueError(f"laps {self.laps}: must be >= 1")


def _run(spec: _DriftSpec, cfg, out_dir) -> dict:
    spec.validate()
    return {"laps": spec.laps}


def test_a_registered_experiment_is_listed_and_checks_its_own_spec():
    experiments()  # the built-ins first
    EXPERIMENTS.register("drift", Experiment("drift", _DriftSpec, _run, dict, "a lap's drift"))
    try:
        entry = experiments().get("drift")
        assert entry.run(entry.spec(laps=2), None, None) == {"laps": 2}
        with pytest.raises(ValueError, match="^laps 0: must be >= 1$"):
            entry.run(entry.spec(laps=0), None, None)
        assert experiments().names()[-1] == "drift" and "payload" in experiments()
        with pytest.raises(ValueError, match="experiment 'drift' is already registered"):
            EXPERIMENTS.register("drift", entry)
    finally:
        EXPERIMENTS.unregister("drift")
    assert "drift" not in experiments()
