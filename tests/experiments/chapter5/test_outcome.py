"""The main outcome under test: the eight chapter 5 runs may not get worse against
the thesis than the committed scorecard; the right wheel tracks worse than the left (§5.1.3);
a payload loads the motors (§5.1.4)."""

import json
import tempfile
from pathlib import Path

import numpy as np
import pytest

from amr_twin.model.config import load_config
from amr_twin.experiments.chapter5 import experiment as chapter5
from amr_twin.experiments.chapter5.scorecard import SCORECARD, scorecard, worse
from amr_twin.assembly.twin import TwinOptions
from amr_twin.assembly.command import Command
from amr_twin.recording.run import run_command


@pytest.fixture(scope="module")
def suite():
    results = chapter5.run(load_config(), jobs=2, progress=False)
    return chapter5.report(results, Path(tempfile.mkdtemp())).as_json()


def test_the_header_counts_every_run_the_progress_bar_counts(suite):
    """ "8 runs, 132 simulated s" left out the 8 rolling-resistance study runs."""
    assert (len(suite["runs"]), suite["study_runs"]) == (8, 8)
    assert (
        suite["sim_s"] == 132.0 and suite["study_sim_s"] == 128.0
    )  # runs 3 and 7 (16 s) at four Crr


def test_no_check_worse_than_the_committed_scorecard(suite):
    """To accept a change that moves the twin away from the thesis, rewrite the scorecard on
    purpose: python -m amr_twin.experiments.chapter5.scorecard (and say why in the commit)."""
    committed = json.loads(SCORECARD.read_text())
    now = scorecard(suite)
    assert worse(committed, now) == []
    assert set(now["checks"]) == set(committed["checks"])


def test_the_committed_scorecard_is_what_the_runs_give_now(suite):
    """The documents quote the scorecard (experiments/documents/figures.py): its values may not
    drift from the code's, better or worse. Within 1e-3: the runs are deterministic."""
    import math

    committed, now = json.loads(SCORECARD.read_text()), scorecard(suite)
    drifted = [
        f"{k}: {c['twin']} committed, {now['checks'][k]['twin']} now"
        for k, c in committed["checks"].items()
        if (c["twin"] is None) != (now["checks"][k]["twin"] is None)
        or c["twin"] is not None
        and not math.isclose(c["twin"], now["checks"][k]["twin"], rel_tol=1e-3, abs_tol=1e-3)
    ]
    counts = (
        "passed",
        "checks_total",
        "true_passed",
        "true_checks_total",
        "oscillation_published_passed",
    )
    drifted += [
        f"{k}: {committed[k]} committed, {now[k]} now" for k in counts if committed[k] != now[k]
    ]
    assert not drifted, "run python -m amr_twin.experiments.documents.figures: " + "; ".join(
        drifted[:6]
    )


def test_worse_finds_a_check_that_leaves_its_band():
    committed = {
        "passed": 2,
        "checks": {
            "a": {"twin": 0.5, "band": [0.3, 0.7], "unit": "s"},
            "b": {"twin": 9.0, "band": [0.0, 3.0], "unit": "RPM"},
        },
    }
    better = {
        "passed": 2,
        "checks": {"a": {"twin": 0.6, "band": [0.3, 0.7]}, "b": {"twin": 3.2, "band": [0.0, 3.0]}},
    }
    assert worse(committed, better) == []
    left_band = {
        "passed": 1,
        "checks": {"a": {"twin": 0.8, "band": [0.3, 0.7]}, "b": {"twin": 9.2, "band": [0.0, 3.0]}},
    }
    found = worse(committed, left_band)
    assert len(found) == 2 and found[0].startswith("a:") and "passed" in found[1]
    assert worse(
        committed,
        {
            "passed": 2,
            "checks": {
                "a": {"twin": None, "band": [0.3, 0.7]},
                "b": {"twin": 9.0, "band": [0.0, 3.0]},
            },
        },
    )


def test_right_wheel_tracks_worse_than_the_left(suite):
    """§5.1.3: "the performances of the right DC motor wheel are worse" (runs 1 and 2, the same
    76.39 RPM step on each wheel alone): the calibrated right wheel (its own board and motor) ends
    further from its reference and its true speed overshoots more. Its published overshoot above its
    own final value is no larger than the left's, which the report's findings say (a miss)."""
    by_run = {r["run"]: r for r in suite["runs"]}
    left, right = by_run[1]["wheels"]["left"], by_run[2]["wheels"]["right"]
    assert abs(right["published"]["steady_error"]) > abs(left["published"]["steady_error"]) + 0.1
    assert right["true"]["overshoot"] > left["true"]["overshoot"] + 0.5
    assert right["published"]["overshoot"] < 2.0  # outside the thesis' 2-6 RPM: a miss, said
    finding = next(f for f in suite["findings"]["findings"] if f["key"] == "overshoot_right")
    assert finding["verdict"] == "not reproduced"


def test_unloaded_wheels_end_in_the_dead_zone(suite):
    """§5.1.3's "almost perfect track": every wheel of runs 1-6 ends within listing 4.11's 4 RPM
    (the calibration's runs 4-6 targets; with one gain for both boards three ended outside)."""
    errors = [
        w["published"]["steady_error"]
        for r in suite["runs"]
        if r["payload_kg"] == 0
        for w in r["wheels"].values()
    ]
    assert len(errors) == 10 and max(abs(e) for e in errors) < 4.0


def test_motor_current_rises_with_payload():
    """Acceptance: empty world, improved firmware, 0.7 m/s for 16 s; the motor
    current over the last 4 s, both wheels, rises 0 < 20 < 40 kg, by at least 0.3 A."""
    current = []
    for mass_kg in (0.0, 20.0, 40.0):
        cfg = load_config(sets=[f"payload.mass_kg={mass_kg}"])
        s = run_command(
            cfg,
            Command("linear", speed_m_s=0.7),
            16.0,
            TwinOptions(firmware="improved", world="empty"),
        ).series
        tail = s.t_s >= 12.0
        assert np.abs(s.true_rpm[tail].mean(axis=0) - 53.48).max() < 2.0  # it does track
        current.append(float(s.current_a[tail].mean()))
    assert current[0] < current[1] < current[2]
    assert current[2] - current[0] >= 0.3
