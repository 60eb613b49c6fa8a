"""The thesis' chapter 5 findings (experiments/chapter5/findings.py), judged on hand-built metrics
objects.

Each finding is built once on the edge of its rule, reproduced, and then moved just across it, so a
verdict that ignored the figure it is about, or compared the wrong way, fails.
"""

import copy

import pytest

from amr_twin.controllers.firmware_params import FaithfulParams
from amr_twin.experiments.chapter5 import criteria
from amr_twin.experiments.chapter5 import findings as found
from amr_twin.experiments.chapter5.timing_bound import TIMINGS, timing_bounds

REFERENCES = {
    1: (76.39, 0.0),
    2: (0.0, 76.39),
    3: (53.48, 53.48),
    4: (-91.67, -91.67),
    5: (99.2, 60.8),
    6: (60.8, 99.2),
    7: (53.48, 53.48),
    8: (99.2, 60.8),
}
TIMES = {
    "delay_s": 0.5,
    "rise_s": 1.0,
    "peak_s": 1.1,
    "settling_s": 1.3,
}  # the > 75 RPM and settling bands


def _wheel(name: str, ref: float, overshoot: float, steady: float, true_overshoot: float) -> dict:
    pub = dict(TIMES, overshoot=overshoot, steady_error=steady)
    true = dict(TIMES, overshoot=true_overshoot, steady_error=steady)
    return {
        "reference_rpm": ref,
        "step_class": criteria.step_class(ref),
        "samples": 10,
        "published": pub,
        "true": true,
        "checks": criteria.judge(name, ref, pub),
        "true_checks": criteria.judge(name, ref, true),
    }


def _data(**over) -> dict:
    """Metrics on which every finding is reproduced, each at the edge of its rule: runs 2/1 right
    4.0 vs left 3.0 RPM (margin 1), runs 3-8 right above left in 4 of 6, unloaded wheels at +-3.9
    RPM, all four 20 kg wheels raised, 3 of 4 comparisons more on each signal, every attainable
    timing in its band (the small steps' delay, rise and peak, out of reach, fail)."""
    overshoot = {(2, "right"): (4.0, 5.0), (1, "left"): (3.0, 4.0)}
    for n in (3, 4, 5, 6):
        overshoot[(n, "right")], overshoot[(n, "left")] = (2.0, 2.0), (1.0, 1.0)
    for n in (7, 8):
        overshoot[(n, "right")], overshoot[(n, "left")] = (1.0, 1.0), (2.0, 2.0)
    overshoot.update(over.get("overshoot", {}))
    steady = {key: (3.9 if key[0] % 2 else -3.9) for key in overshoot}
    steady.update(over.get("steady", {}))
    runs = []
    for n, refs in REFERENCES.items():
        wheels = {
            name: _wheel(
                name, ref, overshoot[(n, name)][0], steady[(n, name)], overshoot[(n, name)][1]
            )
            for name, ref in zip(("left", "right"), refs)
            if ref
        }
        runs.append({"run": n, "payload_kg": 20.0 if n >= 7 else 0.0, "wheels": wheels})
    raised = over.get("raised", [True] * 4)
    pairs = [(7, 3, "left"), (7, 3, "right"), (8, 5, "left"), (8, 5, "right")]
    duty = [
        {
            "loaded_run": r,
            "unloaded_run": u,
            "wheel": w,
            "raised": ok,
            "loaded": {"counts": 12.0 if ok else 11.0},
            "unloaded": {"counts": 11.0},
        }
        for (r, u, w), ok in zip(pairs, raised)
    ]
    pub, true = over.get("oscillation", ([True, True, True, False], [False, True, True, True]))
    comparisons = [
        {"verdict": "pass" if p else "fail", "true_verdict": "pass" if t else "fail"}
        for p, t in zip(pub, true)
    ]
    return {
        "firmware": over.get("firmware", "faithful"),
        "runs": runs,
        "comparisons": comparisons,
        "payload_duty": duty,
    }


def _verdicts(data: dict) -> dict:
    return {f.key: f.verdict for f in found.findings(data).findings}


def test_the_edge_case_reproduces_every_finding():
    assert _verdicts(_data()) == {
        "overshoot_right": "reproduced",
        "tracking": "reproduced",
        "duty_raised": "reproduced",
        "oscillation": "reproduced",
        "timings": "reproduced",
    }


@pytest.mark.parametrize(
    "change, why",
    [
        ({(2, "right"): (3.9, 5.0)}, "right 3.90 vs left 3.00"),  # right only 0.9 above the left
        ({(1, "left"): (3.1, 4.0), (2, "right"): (4.2, 5.0)}, "left 0-3"),  # left above its band
        ({(2, "right"): (6.1, 7.5)}, "right 6.10"),  # right above its band
        ({(2, "right"): (4.0, 4.9)}, "true 4.90 vs 4.00"),  # the true speed's order not kept
        ({(6, "right"): (1.0, 1.0)}, "in 3 of 6 (needs 4)"),  # runs 3-8: only 3 of 6
    ],
)
def test_the_right_wheel_overshoot_finding_flips_just_across_its_rule(change, why):
    (finding,) = [
        f for f in found.findings(_data(overshoot=change)).findings if f.key == "overshoot_right"
    ]
    assert finding.verdict == "not reproduced" and why in finding.why


def test_the_right_wheel_overshoot_is_not_judged_without_runs_1_and_2():
    data = _data()
    data["runs"] = [r for r in data["runs"] if r["run"] > 2]
    assert _verdicts(data)["overshoot_right"] == "not judged"


def test_tracking_uses_the_firmware_dead_zone_and_only_the_unloaded_runs():
    assert found.DEAD_ZONE_RPM == FaithfulParams().threshold_control_rpm
    assert (
        _verdicts(_data(steady={(7, "left"): 12.0}))["tracking"] == "reproduced"
    )  # 20 kg: not this finding
    data = _data(steady={(4, "right"): -4.1})
    (finding,) = [f for f in found.findings(data).findings if f.key == "tracking"]
    assert finding.verdict == "not reproduced"
    assert "9 of 10" in finding.why and "run 4 right -4.10" in finding.why


def test_the_duty_finding_needs_every_20kg_wheel_raised():
    assert _verdicts(_data(raised=[True, True, True, False]))["duty_raised"] == "not reproduced"
    data = _data()
    data["payload_duty"] = []
    assert _verdicts(data)["duty_raised"] == "not judged"


@pytest.mark.parametrize(
    "pub, true, verdict",
    [
        ([True, True, True, False], [True, True, True, False], "reproduced"),
        (
            [True, True, False, False],
            [True, True, True, True],
            "not reproduced",
        ),  # 2 of 4 published
        ([True, True, True, True], [True, False, True, False], "not reproduced"),  # 2 of 4 true
    ],
)
def test_the_oscillation_finding_needs_three_of_four_on_both_signals(pub, true, verdict):
    assert _verdicts(_data(oscillation=(pub, true)))["oscillation"] == verdict


def test_the_bound_is_one_revolution_at_the_reference_and_marks_the_small_steps_unattainable():
    bounds = {(b.run, b.wheel, b.metric): b for b in found.findings(_data()).bounds}
    run3 = {m: bounds[(3, "left", m)] for m in TIMINGS}
    assert run3["delay_s"].bound_s == pytest.approx(30 / 53.48)
    assert run3["rise_s"].bound_s == pytest.approx(48 / 53.48)
    assert run3["peak_s"].bound_s == pytest.approx(60 / 53.48)
    assert run3["settling_s"].bound_s == pytest.approx((1 - 4 / 53.48) * 60 / 53.48)
    assert [run3[m].attainable for m in TIMINGS] == [False, False, False, True]
    assert all(bounds[(4, "left", m)].attainable for m in TIMINGS)  # 91.67 RPM: 0.33, 0.52, 0.65 s
    # the peak band of a small step ends at 0.8 s: one revolution at exactly 75 RPM reaches it, 74.9
    # does not
    edge = timing_bounds({1: {"run": 1, "wheels": {"left": _wheel("left", 75.0, 0, 0, 0)}}})
    below = timing_bounds({1: {"run": 1, "wheels": {"left": _wheel("left", 74.9, 0, 0, 0)}}})
    assert [b.attainable for b in edge if b.metric == "peak_s"] == [True]
    assert [b.attainable for b in below if b.metric == "peak_s"] == [False]


def test_the_improved_firmware_has_no_unattainable_check():
    split = found.findings(_data(firmware="improved")).checks
    assert split.unattainable == 0 and split.attainable == 14 * 6 + 4


def test_the_timings_are_reproduced_when_every_attainable_check_passes():
    data = (
        _data()
    )  # the small steps' delay (0.5 s against 0.1-0.3), rise and peak fail: out of reach
    assert _verdicts(data)["timings"] == "reproduced"
    split = found.findings(data).checks
    assert (split.unattainable, split.unattainable_passed) == (7 * 3, 0)
    # fails among the attainable: one comparison, the right wheel's 1 RPM overshoot of runs 7 and 8
    assert (split.attainable, split.attainable_passed) == (14 * 6 + 4 - 21, 14 * 6 + 4 - 21 - 3)
    broken = copy.deepcopy(data)
    broken["runs"][0]["wheels"]["left"]["checks"]["rise_s"]["verdict"] = (
        "fail"  # 76.39 RPM: attainable
    )
    assert _verdicts(broken)["timings"] == "not reproduced"


def test_the_lines_give_each_finding_its_verdict_then_the_counts_then_the_bound():
    text = found.lines(found.findings(_data()).as_json())
    assert len(text) == 5 + 2
    assert text[0].startswith("[reproduced] right wheel overshoots") and "runs 3-8" in text[0]
    assert (
        text[4].startswith("[reproduced] delay, rise, peak, settling times")
        and "35 of 35 pass" in text[4]
    )
    assert text[5].startswith("attainable checks passed ")
    assert text[6].startswith("unattainable under listing 4.12") and "21 checks, 0 pass" in text[6]
    assert "T = 1.12 s at 53.48 RPM (runs 3, 7: delay >= 0.56 > 0.3, rise >= 0.90 > 0.7" in text[6]
