"""The typed chapter 5 metrics (experiments/chapter5/metrics.py) and metrics.json written from
them."""

import json

import pytest

from amr_twin.experiments.chapter5 import experiment as chapter5
from amr_twin.experiments.chapter5.metrics import (
    Chapter5Metrics,
    Check,
    OscillationComparison,
    metrics,
)
from amr_twin.model.config import load_config


@pytest.fixture(scope="module")
def typed():
    results = chapter5.run(load_config(), runs=[3, 7], duration_s=4.0, progress=False, study=False)
    return metrics(results)


def test_the_metrics_are_typed_down_to_each_check(typed):
    assert isinstance(typed, Chapter5Metrics) and [r.run for r in typed.runs] == [3, 7]
    assert set(typed.runs[0].wheels) == {"left", "right"}
    check = typed.runs[0].wheels["left"].checks["rise_s"]
    assert (
        isinstance(check, Check)
        and check.verdict in ("pass", "fail")
        and check.band[0] <= check.band[1]
    )
    assert (
        all(isinstance(c, OscillationComparison) for c in typed.comparisons)
        and len(typed.comparisons) == 2
    )


def test_the_counts_take_the_oscillation_comparisons_among_the_published_checks(typed):
    banded = [c for r in typed.runs for w in r.wheels.values() for c in w.checks.values()]
    assert typed.summary.checks == len(banded) + len(typed.comparisons) == 2 * 2 * 6 + 2
    assert typed.summary.true_checks == len(banded)
    fails = sum(c.verdict == "fail" for c in banded) + sum(
        c.verdict == "fail" for c in typed.comparisons
    )
    assert typed.summary.passed == typed.summary.checks - fails
    true_banded = [c for r in typed.runs for w in r.wheels.values() for c in w.true_checks.values()]
    assert typed.summary.true_passed == sum(c.verdict == "pass" for c in true_banded)
    assert [c.twin for c in true_banded] != [
        c.twin for c in banded
    ]  # the true speed, not the samples


def test_the_json_is_written_from_the_records_in_their_order(typed):
    out = json.loads(json.dumps(typed.as_json(), allow_nan=False))
    assert list(out)[:4] == ["firmware", "jobs", "wall_s", "sim_s"] and list(out)[-1] == "summary"
    assert "firmware_comparison" not in out and "spread" not in out  # only when made
    left = out["runs"][1]["wheels"]["left"]
    assert list(left) == [
        "reference_rpm",
        "step_class",
        "samples",
        "published",
        "true",
        "checks",
        "true_checks",
    ]
    assert (
        left["checks"]["rise_s"]["verdict"] == typed.runs[1].wheels["left"].checks["rise_s"].verdict
    )
    assert out["summary"] == {
        "checks": 26,
        "passed": typed.summary.passed,
        "true_checks": 24,
        "true_passed": typed.summary.true_passed,
    }


def test_a_run_whose_timestep_the_tyres_guard_halved_says_so_in_metrics_json():
    """Stiff longitudinal tyre corner: run 8's 20 kg gives S = 2.15 at 1 ms (halved to 0.5 ms), run
    3's empty robot 1.12 (kept); only run 8 carries the record."""
    cfg = load_config(
        sets=[
            "wheel.slip_stiffness_per_n=25",
            "wheel.relaxation_length_longitudinal_m=0.02",
            "wheel.tyre_loss_time_s=0.01",
        ]
    )
    written = metrics(
        chapter5.run(cfg, runs=[3, 8], duration_s=1.0, progress=False, study=False)
    ).as_json()
    runs = {r["run"]: r for r in json.loads(json.dumps(written))["runs"]}
    assert "tyre_timestep" not in runs[3]
    assert (
        runs[8]["tyre_timestep"]["timestep_s"] == 0.0005
        and runs[8]["tyre_timestep"]["halvings"] == 1
    )
