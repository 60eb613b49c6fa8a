"""§5.1.4 on the plant: 20 kg moves run 7's wheels out of the PI's dead zone from a rolling
resistance inside the sourced ranges, and the duty comparison and the study's threshold read the
runs right."""

from __future__ import annotations

import pytest

from amr_twin.experiments.chapter5 import experiment as chapter5
from amr_twin.experiments.chapter5 import payload
from amr_twin.model.config import load_config


@pytest.fixture(scope="module")
def runs_by_crr():
    out = {}
    for crr in (0.015, 0.025):
        cfg = load_config(
            sets=[f"wheel.rolling_resistance={crr}", f"caster.rolling_resistance={crr}"]
        )
        out[crr] = chapter5.run(cfg, jobs=2, runs=[3, 7], progress=False, study=False)["runs"]
    return out


def test_from_the_upper_half_of_the_ranges_20_kg_makes_the_pi_raise_the_duty(runs_by_crr):
    """At 0.025 (tyres 0.010-0.025, balls 0.005-0.03) both loaded wheels of run 7 fall more than 4
    RPM below the reference on the unloaded duty, and the PI adds a count; unloaded, run 3 keeps its
    duty."""
    comps = payload.duty_comparison(runs_by_crr[0.025])
    assert [c["wheel"] for c in comps] == ["left", "right"]
    assert all(
        c["raised"] and c["loaded"]["counts"] >= c["unloaded"]["counts"] + 0.5 for c in comps
    )
    ref = comps[0]["reference_rpm"]
    early = [r for r in runs_by_crr[0.025] if r["run"] == 7][0]["raw"]
    for w in (
        0,
        1,
    ):  # the loaded published speed before the PI's raise: outside the 4 RPM dead zone
        counts, t = early["pwm_counts"][:, w], early["t_s"]
        raise_s = t[(counts > counts[(t > 3.0).argmax()]) & (t > 3.0)][0]
        pub = early["published"][w]
        before = pub[(pub[:, 0] > 3.0) & (pub[:, 0] < raise_s), 1]
        assert len(before) >= 2 and before.max() < ref - 4.0


def test_with_the_shipped_coefficient_the_loaded_wheels_stay_in_the_dead_zone(runs_by_crr):
    comps = payload.duty_comparison(runs_by_crr[0.015])
    assert not any(c["raised"] for c in comps)
    assert all(-4.0 <= c["loaded"]["published_rpm"] - c["reference_rpm"] < -2.0 for c in comps)


def _comp(run, wheel, loaded, unloaded):
    return {
        "crr": None,
        "loaded_run": run,
        "wheel": wheel,
        "raised": loaded > unloaded,
        "loaded": {"counts": loaded},
        "unloaded": {"counts": unloaded},
    }


def test_the_threshold_is_the_lowest_coefficient_raising_both_run_7_wheels():
    shipped = [_comp(7, "left", 11, 11), _comp(7, "right", 11, 11)]
    study = [
        {**_comp(7, "left", 12, 11), "crr": 0.02},
        {**_comp(7, "right", 11, 11), "crr": 0.02},
        {**_comp(7, "left", 12, 11), "crr": 0.025},
        {**_comp(7, "right", 12, 11), "crr": 0.025},
        {**_comp(8, "right", 12, 11), "crr": 0.02},
    ]
    assert payload.threshold_crr(shipped, study, 0.015) == 0.025
    assert payload.threshold_crr(shipped, study[:2], 0.015) is None
