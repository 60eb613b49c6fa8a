"""Chapter 5's criteria: the verdict logic on synthetic metrics, and how the report states it."""

from amr_twin.experiments.chapter5 import criteria

CHECKED = {"delay_s", "rise_s", "peak_s", "settling_s", "overshoot", "steady_error"}


def test_judge_uses_each_wheels_own_step_size():
    good_small = {
        "delay_s": 0.2,
        "rise_s": 0.5,
        "peak_s": 0.6,
        "settling_s": 1.3,
        "overshoot": 4.0,
        "steady_error": -3.5,
    }
    checks = criteria.judge("right", 60.8, good_small)
    assert {k: c["verdict"] for k, c in checks.items()} == dict.fromkeys(CHECKED, "pass")
    assert checks["delay_s"]["band"] == [0.1, 0.3]
    large = criteria.judge("left", 99.2, good_small)  # same numbers, > 75 RPM bands
    assert large["delay_s"]["band"] == [0.3, 0.7] and large["delay_s"]["verdict"] == "fail"
    assert large["overshoot"]["band"] == [0.0, 3.0] and large["overshoot"]["verdict"] == "fail"
    assert criteria.judge("left", -91.67, {})["rise_s"]["verdict"] == "fail"  # unmeasured fails
    assert criteria.judge("left", 75.0, {})["rise_s"]["band"] == [0.3, 0.7]  # 75 RPM is still small


def test_a_steady_offset_is_judged_on_its_own():
    """Run 6's right wheel: a monotone rise to +5.97 RPM over 99.20 has no overshoot,
    which passes nothing for the right wheel (band 2-6 RPM), and its offset fails on its own;
    an offset inside the faithful PI's 4 RPM dead zone passes, either sign."""
    offset = criteria.judge("right", 99.2, {"overshoot": 0.0, "steady_error": 5.97})
    assert offset["overshoot"]["verdict"] == "fail" and offset["steady_error"]["verdict"] == "fail"
    assert offset["steady_error"]["band"] == [-4.0, 4.0] and offset["steady_error"]["thesis"] == 0.0
    for error, verdict in ((-3.9, "pass"), (3.9, "pass"), (-4.1, "fail"), (4.1, "fail")):
        assert (
            criteria.judge("left", 53.48, {"steady_error": error})["steady_error"]["verdict"]
            == verdict
        )


def _synthetic_run(number, left, right, true_left=0.0, true_right=0.0):
    return {
        "run": number,
        "wheels": {
            "left": {"published": {"oscillation": left}, "true": {"oscillation": true_left}},
            "right": {"published": {"oscillation": right}, "true": {"oscillation": true_right}},
        },
    }


def test_oscillation_comparison():
    runs = [
        _synthetic_run(3, 1.0, 2.0, 5.0, 5.0),
        _synthetic_run(7, 3.0, 1.0, 4.0, 6.0),
        _synthetic_run(5, 1.0, None),
        _synthetic_run(8, 2.0, 4.0, None, 1.0),
    ]
    out = criteria.compare_oscillation(runs)
    verdicts = {(c["loaded_run"], c["wheel"]): c["verdict"] for c in out}
    assert verdicts == {
        (7, "left"): "pass",
        (7, "right"): "fail",
        (8, "left"): "pass",
        (8, "right"): "fail",
    }
    true = {(c["loaded_run"], c["wheel"]): c["true_verdict"] for c in out}
    assert true == {
        (7, "left"): "fail",
        (7, "right"): "pass",
        (8, "left"): "fail",
        (8, "right"): "pass",
    }
    assert all(c["measure"] == criteria.OSCILLATION_MEASURE for c in out)
    overall = criteria.oscillation_verdict(out)
    assert (overall["comparisons"], overall["published_passed"], overall["true_passed"]) == (
        4,
        2,
        2,
    )
    assert overall["verdict"] == "fail"  # the claim needs every comparison
    assert (
        criteria.oscillation_verdict([c for c in out if c["verdict"] == "pass"])["verdict"]
        == "pass"
    )
    assert criteria.oscillation_verdict([])["verdict"] == "fail"


def test_report_states_the_oscillation_measure_and_verdict():
    from amr_twin.experiments.chapter5.report import markdown

    runs = [_synthetic_run(3, 1.0, 2.0, 5.0, 5.0), _synthetic_run(7, 3.0, 4.0, 6.0, 7.0)]
    comparisons = criteria.compare_oscillation(runs)
    for run, payload in zip(runs, (0.0, 20.0)):
        run.update(title=f"run {run['run']}", payload_kg=payload, errors=[])
        for w in run["wheels"].values():
            w.update(reference_rpm=53.48, step_class="small", samples=5, checks={}, true_checks={})
    data = {
        "firmware": "faithful",
        "jobs": 1,
        "wall_s": 1.0,
        "sim_s": 32.0,
        "judged_on": "published samples",
        "definitions": criteria.DEFINITIONS,
        "settling_band": "4 RPM",
        "oscillation": "excess total variation",
        "bands": [],
        "runs": runs,
        "comparisons": comparisons,
        "oscillation_verdict": criteria.oscillation_verdict(comparisons),
        "summary": {"checks": 2, "passed": 2, "true_checks": 0, "true_passed": 0},
    }
    text = markdown(data)
    assert "2 runs (32 simulated s) in 1.0 s wall time" in text  # no study runs: none counted
    study = markdown({**data, "study_runs": 8, "study_sim_s": 128.0})
    assert (
        "2 runs (32 simulated s) and 8 rolling-resistance study runs (128 s), 10 runs and 160 "
        "simulated s" in study
    )
    assert "Named measure: **excess total variation**" in text
    assert "| 7 | 20 | right | 53.48 | 4.00 | 7.00 |" in text  # per run and wheel: published, true
    assert "| 7 | 3 | left | 3.00 / 1.00 | pass | 6.00 / 5.00 | pass |" in text
    assert (
        '"the 20 kg runs oscillate more" holds** — the 20 kg wheel oscillates more in 2 of 2'
        in text
    )


def test_count_checks_counts_the_comparisons_with_the_published_samples_only():
    """The scorecard: published samples' banded metrics plus the oscillation comparisons' published
    verdicts; the true speed's banded metrics apart (the comparisons' true verdicts not counted)."""
    small = {
        "delay_s": 0.2,
        "rise_s": 0.5,
        "peak_s": 0.6,
        "settling_s": 1.3,
        "overshoot": 1.0,
        "steady_error": 0.5,
    }
    late = dict(small, delay_s=0.9, rise_s=2.0)
    runs = [
        {
            "wheels": {
                "left": {
                    "checks": criteria.judge("left", 60.8, small),  # 6 of 6
                    "true_checks": criteria.judge("left", 60.8, late),
                }
            }
        },  # 4 of 6
        {
            "wheels": {
                "right": {
                    "checks": criteria.judge("right", 60.8, late),  # 3 of 6 (overshoot < 2)
                    "true_checks": criteria.judge("right", 60.8, small),
                }
            }
        },
    ]  # 5 of 6
    comparisons = [
        {"verdict": "pass", "true_verdict": "fail"},
        {"verdict": "fail", "true_verdict": "pass"},
    ]
    assert criteria.count_checks(runs, comparisons) == (14, 10, 12, 9)
