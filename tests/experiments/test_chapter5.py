"""Chapter 5 experiment machinery: one short run end to end, and the verdict logic on synthetic metrics."""

import json

import pytest
from typer.testing import CliRunner

from amr_twin.cli.main import app
from amr_twin.model.config import load_config
from amr_twin.experiments import chapter5
from amr_twin.sim.run import run_command

CHECKED = {"delay_s", "rise_s", "peak_s", "settling_s", "overshoot"}


@pytest.fixture(scope="module")
def short_run(tmp_path_factory):
    out = tmp_path_factory.mktemp("ch5")
    results = chapter5.run(load_config(), runs=[3], duration_s=4.0, progress=False)
    chapter5.plot(results, out)
    data = chapter5.report(results, out)
    return out, results, data


def test_metrics_json_structure(short_run):
    out, results, data = short_run
    on_disk = json.loads((out / "metrics.json").read_text())
    assert on_disk == json.loads(json.dumps(data))
    assert {"firmware", "wall_s", "sim_s", "bands", "runs", "comparisons", "summary",
            "oscillation_verdict"} <= set(on_disk)
    assert on_disk["oscillation_verdict"]["comparisons"] == 0  # run 3 alone has no 20 kg twin
    assert "not judged" in (out / "report.md").read_text()
    (run,) = on_disk["runs"]
    assert run["run"] == 3 and run["duration_s"] == 4.0 and "raw" not in run
    assert run["wheel_command"] == pytest.approx([1, 53.47, 1, 53.47], abs=0.01)
    assert set(run["wheels"]) == {"left", "right"}
    for wheel in run["wheels"].values():
        assert wheel["step_class"] == "small" and wheel["samples"] >= 1
        assert set(wheel["checks"]) == CHECKED
        for check in wheel["checks"].values():
            assert set(check) == {"twin", "thesis", "band", "verdict"}
            assert check["verdict"] in ("pass", "fail")
        assert set(wheel["published"]) >= {"delay_s", "rise_s", "peak_s", "overshoot", "settling_s", "oscillation"}
        assert wheel["true"]["reference"] == pytest.approx(53.47, abs=0.01)
    assert (out / "run3.png").stat().st_size > 1000
    assert "| 3 | left |" in (out / "report.md").read_text()
    assert not list(out.glob(".*.tmp"))


def test_rotation_commands_give_the_thesis_wheel_speeds():
    cfg = load_config()
    right = run_command(cfg, chapter5.RUNS[4].command, 0.05).wheel_command
    left = run_command(cfg, chapter5.RUNS[5].command, 0.05).wheel_command
    assert right == pytest.approx([1, 99.20, 1, 60.80], abs=0.01)
    assert left == pytest.approx([1, 60.80, 1, 99.20], abs=0.01)


def test_judge_uses_each_wheels_own_step_size():
    good_small = {"delay_s": 0.2, "rise_s": 0.5, "peak_s": 0.6, "settling_s": 1.3, "overshoot": 4.0}
    checks = chapter5.judge("right", 60.8, good_small)
    assert {k: c["verdict"] for k, c in checks.items()} == dict.fromkeys(CHECKED, "pass")
    assert checks["delay_s"]["band"] == [0.1, 0.3]
    large = chapter5.judge("left", 99.2, good_small)  # same numbers, > 75 RPM bands
    assert large["delay_s"]["band"] == [0.3, 0.7] and large["delay_s"]["verdict"] == "fail"
    assert large["overshoot"]["band"] == [0.0, 3.0] and large["overshoot"]["verdict"] == "fail"
    assert chapter5.judge("left", -91.67, {})["rise_s"]["verdict"] == "fail"  # unmeasured fails
    assert chapter5.judge("left", 75.0, {})["rise_s"]["band"] == [0.3, 0.7]  # 75 RPM is still small


def _synthetic_run(number, left, right, true_left=0.0, true_right=0.0):
    return {"run": number, "wheels": {"left": {"published": {"oscillation": left}, "true": {"oscillation": true_left}},
                                      "right": {"published": {"oscillation": right},
                                                "true": {"oscillation": true_right}}}}


def test_oscillation_comparison():
    runs = [_synthetic_run(3, 1.0, 2.0, 5.0, 5.0), _synthetic_run(7, 3.0, 1.0, 4.0, 6.0),
            _synthetic_run(5, 1.0, None), _synthetic_run(8, 2.0, 4.0, None, 1.0)]
    out = chapter5.compare_oscillation(runs)
    verdicts = {(c["loaded_run"], c["wheel"]): c["verdict"] for c in out}
    assert verdicts == {(7, "left"): "pass", (7, "right"): "fail", (8, "left"): "pass", (8, "right"): "fail"}
    true = {(c["loaded_run"], c["wheel"]): c["true_verdict"] for c in out}
    assert true == {(7, "left"): "fail", (7, "right"): "pass", (8, "left"): "fail", (8, "right"): "pass"}
    assert all(c["measure"] == chapter5.OSCILLATION_MEASURE for c in out)
    overall = chapter5.oscillation_verdict(out)
    assert (overall["comparisons"], overall["published_passed"], overall["true_passed"]) == (4, 2, 2)
    assert overall["verdict"] == "fail"  # the claim needs every comparison
    assert chapter5.oscillation_verdict([c for c in out if c["verdict"] == "pass"])["verdict"] == "pass"
    assert chapter5.oscillation_verdict([])["verdict"] == "fail"


def test_report_states_the_oscillation_measure_and_verdict():
    from amr_twin.experiments.chapter5_report import markdown

    runs = [_synthetic_run(3, 1.0, 2.0, 5.0, 5.0), _synthetic_run(7, 3.0, 4.0, 6.0, 7.0)]
    comparisons = chapter5.compare_oscillation(runs)
    for run, payload in zip(runs, (0.0, 20.0)):
        run.update(title=f"run {run['run']}", payload_kg=payload, errors=[])
        for w in run["wheels"].values():
            w.update(reference_rpm=53.48, step_class="small", samples=5, checks={})
    data = {"firmware": "faithful", "jobs": 1, "wall_s": 1.0, "sim_s": 32.0, "judged_on": "published samples",
            "settling_band": "4 RPM", "oscillation": "excess total variation", "bands": [], "runs": runs,
            "comparisons": comparisons, "oscillation_verdict": chapter5.oscillation_verdict(comparisons),
            "summary": {"checks": 2, "passed": 2}}
    text = markdown(data)
    assert "Named measure: **excess total variation**" in text
    assert "| 7 | 20 | right | 53.48 | 4.00 | 7.00 |" in text  # per run and wheel: published, true
    assert "| 7 | 3 | left | 3.00 / 1.00 | pass | 6.00 / 5.00 | pass |" in text
    assert '"the 20 kg runs oscillate more" holds** — the 20 kg wheel oscillates more in 2 of 2' in text


def test_cli_rejects_bad_jobs_and_writes_nothing(tmp_path):
    result = CliRunner().invoke(app, ["experiment", "chapter5", "--out", str(tmp_path / "x"), "--jobs", "0"])
    assert result.exit_code == 2 and "--jobs" in result.output
    assert not (tmp_path / "x").exists()
