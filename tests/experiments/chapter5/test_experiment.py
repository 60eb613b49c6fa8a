"""Chapter 5 experiment machinery: one short run end to end, the rotation commands, the CLI's
checks."""

import json

import pytest
from typer.testing import CliRunner

from amr_twin.cli.main import app
from amr_twin.model.config import load_config
from amr_twin.experiments.chapter5 import experiment as chapter5
from amr_twin.experiments.chapter5.runs import RUNS
from amr_twin.recording.run import run_command

CHECKED = {"delay_s", "rise_s", "peak_s", "settling_s", "overshoot", "steady_error"}


@pytest.fixture(scope="module")
def short_run(tmp_path_factory):
    out = tmp_path_factory.mktemp("ch5")
    results = chapter5.run(load_config(), runs=[3], duration_s=4.0, progress=False)
    chapter5.plot(results, out)
    data = chapter5.report(results, out).as_json()
    return out, results, data


def test_metrics_json_structure(short_run):
    out, results, data = short_run
    on_disk = json.loads((out / "metrics.json").read_text())
    assert on_disk == json.loads(json.dumps(data))
    assert {
        "firmware",
        "wall_s",
        "sim_s",
        "bands",
        "runs",
        "comparisons",
        "summary",
        "oscillation_verdict",
    } <= set(on_disk)
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
        assert set(wheel["published"]) >= {
            "delay_s",
            "rise_s",
            "peak_s",
            "overshoot",
            "settling_s",
            "oscillation",
        }
        assert wheel["true"]["reference"] == pytest.approx(53.47, abs=0.01)
    assert (out / "run3.png").stat().st_size > 1000
    assert "| 3 | left |" in (out / "report.md").read_text()
    assert not list(out.glob(".*.tmp"))


def test_rotation_commands_give_the_thesis_wheel_speeds():
    cfg = load_config()
    right = run_command(cfg, RUNS[4].command, 0.05).wheel_command
    left = run_command(cfg, RUNS[5].command, 0.05).wheel_command
    assert right == pytest.approx([1, 99.20, 1, 60.80], abs=0.01)
    assert left == pytest.approx([1, 60.80, 1, 99.20], abs=0.01)


def test_cli_rejects_bad_jobs_and_writes_nothing(tmp_path):
    result = CliRunner().invoke(
        app, ["experiment", "chapter5", "--out", str(tmp_path / "x"), "--jobs", "0"]
    )
    assert result.exit_code == 2 and "--jobs" in result.output
    assert not (tmp_path / "x").exists()


def test_a_backward_run_has_one_sign_in_metrics_json_and_report_md(tmp_path):
    """Run 4's reference was -91.67 in report.md and +91.67 in metrics.json. Every signed
    value (reference, final value, steady error) carries the reference's sign in both."""
    results = chapter5.run(load_config(), runs=[4], duration_s=4.0, progress=False)
    data = chapter5.report(results, tmp_path).as_json()
    report = (tmp_path / "report.md").read_text()
    for name, wheel in data["runs"][0]["wheels"].items():
        assert wheel["reference_rpm"] == pytest.approx(-91.67, abs=0.01)
        for source in ("published", "true"):
            m = wheel[source]
            assert (
                m["reference"] == pytest.approx(wheel["reference_rpm"]) and m["final_value"] < -80
            )
            assert m["steady_error"] == pytest.approx(m["final_value"] - m["reference"])
        assert f"| 4 | {name} | -91.67 |" in report
    assert (
        "| 4 | left | 91.67 |" not in report
        and "samples |" in report.split("## True wheel speed")[0]
    )
    assert (
        "samples" not in report.split("## True wheel speed")[1].split("\n\n")[2]
    )  # no repeated sample counts
