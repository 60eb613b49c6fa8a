"""``amr-twin experiment umbmark`` end to end on a short case (three robots, one square each way and
phase), and its refusals (one line, exit 2, nothing written).

What the case must show, each a figure a user reads off the report: the calibration written for
each robot's odometry reduces its E_max,syst (Borenstein's claim, here on every seed), UMBmark
finds the robot's drawn wheel diameters, the files are there and agree (the YAML the odometry
node reads is the JSON's), and the same robots are driven with the rigid contact. (The spreads
need several runs a direction: tests/experiments/umbmark/test_seeds.py.)"""

import json

import pytest
from typer.testing import CliRunner

from amr_twin.cli.main import app
from amr_twin.controllers.odometry_calibration import load
from amr_twin.experiments.fusion import robot as fusion_robot
from amr_twin.model.config import load_config

SEEDS = [0, 1, 2]


@pytest.fixture(scope="module")
def report(tmp_path_factory):
    out = tmp_path_factory.mktemp("umbmark") / "out"
    res = CliRunner().invoke(
        app,
        [
            "experiment",
            "umbmark",
            "--seeds",
            "0:2",
            "--runs",
            "1",
            "--jobs",
            "2",
            "--no-progress",
            "--out",
            str(out),
        ],
    )
    assert res.exit_code == 0, res.output
    return out, json.loads((out / "metrics.json").read_text()), res.output


def test_the_calibration_reduces_e_max_syst_on_every_robot(report):
    _, data, output = report
    assert [d["seed"] for d in data["per_seed"]] == SEEDS
    for d in data["per_seed"]:
        before, after = d["before"]["node"]["e_max_syst_m"], d["after"]["node"]["e_max_syst_m"]
        assert before > 0.05 and after < before / 3, d["seed"]  # measured 30-50 times smaller
        assert d["reduction"] == pytest.approx(before / after)
    assert data["summary"]["seeds_reduced"] == 3 and "reduction: median" in output


def test_umbmark_finds_each_robots_wheel_diameters(report):
    """E_d against the robot's drawn radii (r_R / r_L): the tyres' own part is below 2e-4."""
    _, data, _ = report
    cfg = load_config()
    for d in data["per_seed"]:
        robot = fusion_robot.draw(cfg, d["seed"])
        r = cfg.wheel.radius_m
        e_d = (r + robot.radius_error_right_m) / (r + robot.radius_error_left_m)
        assert d["before"]["node"]["e_d"] == pytest.approx(e_d, abs=4e-4)


def test_the_files_agree(report):
    out, data, _ = report
    for name in ("report.md", "borenstein.png", "emax.png"):
        assert (out / name).stat().st_size > 1000, name
    assert (out / "borenstein.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    for d in data["per_seed"]:
        cal = load(out / "calibration" / f"seed{d['seed']}.yaml")
        assert cal.wheel_separation_m == pytest.approx(
            d["calibration"]["wheel_separation_m"], abs=1e-6
        )
        assert cal.left_wheel_radius_m == pytest.approx(
            d["calibration"]["left_wheel_radius_m"], abs=1e-6
        )
        assert cal.wheel_separation_m == pytest.approx(0.48 * d["before"]["node"]["e_b"], abs=1e-6)
        assert len(d["before"]["runs"]) == len(d["after"]["runs"]) == 2
    text = (out / "report.md").read_text()
    assert "E_max,syst before calibration" in text and "rigid contact" in text
    nonsyst = [line for line in text.splitlines() if line.startswith("- non-systematic spread")]
    assert (
        len(nonsyst) == 1 and "with the tyre model off" in nonsyst[0]
    )  # both, on the line UMBmark asks for
    assert nonsyst[0].count("±") == 2, nonsyst[0]  # each a mean ± sd (min-max) over the seeds


def test_the_rigid_contact_runs_are_the_same_robots(report):
    """With the tyres on, the same seeds are driven with the rigid contact (the spread's
    comparison): without the tyres' slip their E_max,syst is the wheels' geometry alone."""
    _, data, _ = report
    rigid = data["rigid_per_seed"]
    assert [d["seed"] for d in rigid] == SEEDS and all(
        d["after"] is None and not d["tyres"] for d in rigid
    )
    for d in rigid:
        slip = d["before"]["slip"]["e_max_syst_m"]
        assert slip < 0.003  # no tyre slip: the wheels' true angles and geometry give the pose
    for d in data["per_seed"]:
        assert 0.02 < d["before"]["slip"]["e_max_syst_m"] < 0.08  # the tyres' part, 4 cm


@pytest.mark.parametrize(
    "args, words",
    [
        (["--runs", "0"], "--runs 0: must be in 1..50"),
        (["--runs", "51"], "--runs 51"),
        (["--seeds", "3:1"], "--seeds '3:1'"),
        (
            ["--set", "wheel.tyre_slip=false"],
            "--set wheel.tyre_slip: chosen by this command's --tyres/--no-tyres",
        ),
        (["--set", "sim.floor_friction_field=true"], "--set sim.floor_friction_field"),
        (["--jobs", "0"], "--jobs"),
        (
            ["--seeds", "0:999", "--runs", "50"],
            "300000 squares: about 30.0 h with",
        ),  # and "add --yes"
    ],
)
def test_bad_options_are_refused_in_one_line_before_any_square(tmp_path, args, words):
    out = tmp_path / "out"
    res = CliRunner().invoke(
        app, ["experiment", "umbmark", "--out", str(out), "--no-progress", *args]
    )
    assert (
        res.exit_code == 2 and words in res.output and len(res.output.strip().splitlines()) == 1
    ), res.output
    assert not out.exists()


def test_an_output_that_is_a_file_is_refused(tmp_path):
    out = tmp_path / "report"
    out.write_text("mine")
    res = CliRunner().invoke(
        app, ["experiment", "umbmark", "--out", str(out), "--runs", "1", "--seeds", "0"]
    )
    assert res.exit_code == 2 and "--out" in res.output and out.read_text() == "mine"
