"""docs/reference/faults.md is what the fault study writes now (its figures
once drifted from the code's: 61.4 against 61.5 RPM, chatter 2.5 against 3.4 RPM, -88 against -89
deg)."""

import json
import math

import pytest

from amr_twin.experiments.faults import experiment as faults
from amr_twin.experiments.faults.report import COMMITTED_JSON, PAGE, markdown
from amr_twin.model.config import load_config

REGENERATE = "regenerate it: python -m amr_twin.experiments.documents.figures"


def _committed() -> dict:
    data = json.loads(COMMITTED_JSON.read_text())
    return {"cases": list(dict.fromkeys(r["fault"] for r in data["rows"])), "rows": data["rows"]}


def _differences(old, new, where: str = "") -> list[str]:
    """Where ``new`` differs from ``old``: floats beyond 1e-3 (relative, or absolute near 0),
    anything else at all."""
    if isinstance(old, dict) and isinstance(new, dict):
        keys = sorted(set(old) | set(new))
        return [d for k in keys for d in _differences(old.get(k), new.get(k), f"{where}.{k}")]
    if isinstance(old, float) and isinstance(new, (int, float)) and not isinstance(new, bool):
        same = math.isclose(old, new, rel_tol=1e-3, abs_tol=1e-3)
        return [] if same else [f"{where}: {old} committed, {new} now"]
    return [] if old == new else [f"{where}: {old!r} committed, {new!r} now"]


def test_the_page_is_written_from_its_committed_measures():
    """The page's every figure comes from faults.json, through the report's own code."""
    assert PAGE.read_text() == markdown(_committed(), images="../img"), REGENERATE


def test_the_committed_measures_are_what_the_experiment_gives_now():
    fresh = faults.run(load_config(), jobs=1, progress=False)
    committed = _committed()
    assert fresh["cases"] == committed["cases"], REGENERATE
    now = json.loads(json.dumps(fresh["rows"], default=float))
    diffs = [
        d
        for old, new in zip(committed["rows"], now)
        for d in _differences(old, new, f"{old['fault']} {old['firmware']}")
    ]
    assert not diffs, (
        f"{len(diffs)} figures of {COMMITTED_JSON.name} changed ({REGENERATE}): "
        + "; ".join(diffs[:8])
    )


def test_the_comparison_tolerates_rounding_and_not_a_drift():
    old = {"a": 61.4, "n": 40, "b": None, "c": {"x": 1e-12}}
    assert _differences(old, {"a": 61.4 * (1 + 1e-5), "n": 40, "b": None, "c": {"x": -1e-11}}) == []
    assert len(_differences(old, {"a": 61.5, "n": 41, "b": 0.0, "c": {"x": 0.01}})) == 4
    with pytest.raises(AssertionError):
        assert not _differences({"chatter": 2.5}, {"chatter": 3.4})
