"""Calibration: a log recovers a known plant parameter; the shipped values are what the
thesis fit gives; the bench point is met in the quantity it is judged to be."""

import csv
import re

import pytest
import yaml

from amr_twin.calibration.fit import calibrate, write_params
from amr_twin.calibration.targets import BENCH_CURRENT_A, bench_current_a, read_log, thesis_residual
from amr_twin.model.config import load_config
from amr_twin.assembly.twin import TwinOptions
from amr_twin.model.paths import MODEL_DIR
from amr_twin.assembly.command import Command
from amr_twin.recording.run import run_command

LOG_COMMAND = "motor:left:forward:1.0"


def _write_log(path, gain):
    cfg = load_config(sets=[f"driver_left.gain={gain}"])
    series = run_command(cfg, Command.parse(LOG_COMMAND), 6.0, TwinOptions(world="empty")).series
    with open(path, "w", newline="") as fh:
        out = csv.writer(fh)
        out.writerow(["t_s", "wheel", "rpm", "command"])
        for t, rpm in series.published[0]:
            out.writerow([f"{t:.6f}", "left", f"{rpm:.4f}", LOG_COMMAND])
    return len(series.published[0])


def test_fit_recovers_driver_gain_from_a_log(tmp_path):
    log = tmp_path / "real.csv"
    n = _write_log(log, gain=1.45)
    fit = calibrate(
        str(log),
        base=load_config(sets=["driver_left.gain=1.9"]),
        max_evaluations=14,
        parameters={"driver_left.gain": (1.0, 3.0)},
    )
    assert abs(fit.values["driver_left.gain"] - 1.45) < abs(1.9 - 1.45) / 3
    assert fit.residual < 4.0 * n  # RMS under 2 RPM, half the firmware's 4 RPM dead band
    assert 0 < fit.sigma["driver_left.gain"] < 0.2
    assert (
        fit.evaluations <= 14
    )  # the budget holds (scipy's max_nfev counts steps, not evaluations)
    out = tmp_path / "params.yaml"
    write_params(fit, out)
    cfg = load_config(override_file=out)
    assert cfg.driver_left.gain == pytest.approx(fit.values["driver_left.gain"], abs=1e-4)


def test_shipped_plant_gives_the_residual_amr_yaml_records():
    """The chi^2 written where the calibrated parameters' sources lead (their section of
    models/amr/sources.md) is what the shipped values give."""
    tree = yaml.safe_load((MODEL_DIR / "amr.yaml").read_text())
    sources = {
        tree[s][k]["source"]
        for s, k in (
            ("driver_left", "gain"),
            ("driver_right", "gain"),
            ("motor_left", "ke_v_s_rad"),
            ("motor_right", "friction_nm"),
        )
    }
    assert len(sources) == 1  # one fit, one section
    anchor = re.search(r"sources\.md#([\w-]+)", sources.pop()).group(1)
    text = (MODEL_DIR / "sources.md").read_text()
    heading = next(
        h for h in re.findall(r"^#+ (.*)$", text, re.M) if h.lower().replace(" ", "-") == anchor
    )
    section = text.split(heading, 1)[1].split("\n#", 1)[0]
    recorded = {float(v) for v in re.findall(r"chi\^2 ([0-9.]+)", section)}
    assert len(recorded) == 1
    assert thesis_residual(load_config()) == pytest.approx(recorded.pop(), abs=0.15)


def test_bench_point_is_met_as_a_motor_current():
    """0.38 A at 71.5 RPM, wheel free (listing 4.1): the shipped motors draw it, within the
    calibration's 0.04 A; read as a supply current the same motors would draw a tenth of it."""
    cfg = load_config()
    for wheel in (0, 1):
        assert bench_current_a(cfg, wheel, "motor") == pytest.approx(BENCH_CURRENT_A, abs=0.04)
        assert bench_current_a(cfg, wheel, "supply") < 0.25 * BENCH_CURRENT_A


def test_a_scaled_motor_no_longer_fits():
    """Driver gain and Ke scaled together by 1.1 keep the no-load speed: the true-speed
    timings and the bench point must tell them apart (19.4 against 19.9)."""
    cfg = load_config()
    base = thesis_residual(cfg)
    scaled = load_config(
        sets=[
            f"driver_left.gain={cfg.driver_left.gain * 1.1}",
            f"driver_right.gain={cfg.driver_right.gain * 1.1}",
            f"motor_left.ke_v_s_rad={cfg.motor_left.ke_v_s_rad * 1.1}",
            f"motor_right.ke_v_s_rad={cfg.motor_right.ke_v_s_rad * 1.1}",
        ]
    )
    assert thesis_residual(scaled) > base + 2.0


def test_a_log_with_a_byte_order_mark_reads_as_without(tmp_path):
    """Spreadsheets export UTF-8 with a byte-order mark: the first column is still ``t_s``."""
    plain, marked = tmp_path / "plain.csv", tmp_path / "marked.csv"
    text = "t_s,wheel,rpm,command\n0.5,left,10,linear:0.7\n2.0,left,50,linear:0.7\n"
    plain.write_text(text, encoding="utf-8")
    marked.write_text(text, encoding="utf-8-sig")
    assert marked.read_bytes().startswith(b"\xef\xbb\xbf")
    a, b = read_log(plain), read_log(marked)
    assert a.keys() == b.keys() and all((a[k][w] == b[k][w]).all() for k in a for w in a[k])


def test_log_format_errors_name_the_problem(tmp_path):
    bad = tmp_path / "bad.csv"
    bad.write_text("t_s,wheel,rpm\n0.1,left,3\n")
    with pytest.raises(ValueError, match="missing column"):
        read_log(bad)
    bad.write_text("t_s,wheel,rpm,command\n0.1,left,3,fly:3\n")
    with pytest.raises(ValueError, match="expected linear"):
        read_log(bad)
    bad.write_text("t_s,wheel,rpm,command\n")
    with pytest.raises(ValueError, match="no samples"):
        read_log(bad)


def test_a_log_too_short_to_compare_is_refused_not_scored(tmp_path):
    from typer.testing import CliRunner

    from amr_twin.cli.main import app

    short = tmp_path / "short.csv"
    short.write_text("t_s,wheel,rpm,command\n0.5,left,10,linear:0.7\n2.0,left,50,linear:0.7\n")
    out = tmp_path / "params.yaml"
    res = CliRunner().invoke(
        app, ["calibrate", "--target", str(short), "--out", str(out), "--max-evaluations", "7"]
    )
    assert res.exit_code == 2 and "the log must be longer" in res.stderr and not out.exists()
    assert len(res.stderr.strip().splitlines()) == 1


@pytest.mark.parametrize("budget", [7, 15])
def test_the_fit_never_exceeds_its_evaluation_budget(tmp_path, budget):
    """scipy's max_nfev counts steps, each with a Jacobian of one evaluation per parameter (a
    budget of 2 once made 7): every evaluation is counted, and a budget below one step is
    refused."""
    log = tmp_path / "real.csv"
    _write_log(log, gain=1.45)
    calls = []
    fit = calibrate(
        str(log),
        base=load_config(sets=["driver_left.gain=1.9"]),
        max_evaluations=budget,
        progress=lambda i, n: calls.append(i),
    )
    assert fit.evaluations == len(calls) and 7 <= fit.evaluations <= budget
    with pytest.raises(ValueError, match="max_evaluations 6: at least 7"):
        calibrate(str(log), base=load_config(), max_evaluations=6)


def test_calibrate_prints_a_readable_summary_and_json_on_request(tmp_path):
    """Calibrate printed one unformatted 4 KB JSON line. Now one line per parameter
    (value, 1 sigma) and per feature (a thesis target), the strong correlations named; --json
    for a program. The progress bar goes to stderr."""
    import json

    from typer.testing import CliRunner

    from amr_twin.cli.main import app
    from amr_twin.assembly.command import Command
    from amr_twin.recording.run import run_command

    series = run_command(load_config(), Command("linear", speed_m_s=0.7), 4.0).series
    log = tmp_path / "log.csv"
    log.write_text(
        "t_s,wheel,rpm,command\n"
        + "".join(f"{t},{w},{rpm},linear:0.7\n" for w in (0, 1) for t, rpm in series.published[w])
    )
    args = ["calibrate", "--target", str(log), "--max-evaluations", "7", "--jobs", "1"]
    text = CliRunner().invoke(app, [*args, "--out", str(tmp_path / "a.yaml")])
    assert text.exit_code == 0, text.output
    lines = text.stdout.splitlines()
    assert lines[0].startswith(f"calibrated against {log}: chi^2 ") and max(map(len, lines)) < 160
    for key in ("driver_left.gain", "motor_left.ke_v_s_rad", "motor_right.friction_nm"):
        row = next(line for line in lines if line.startswith(key)).split()
        assert len(row) == 3 and float(row[2]) > 0  # value and its 1 sigma
    assert "correlated (|r| >= 0.9):" in lines
    assert lines[-1] == f"wrote {tmp_path / 'a.yaml'}"
    machine = CliRunner().invoke(app, [*args, "--out", str(tmp_path / "b.yaml"), "--json"])
    (line,) = machine.stdout.strip().splitlines()
    data = json.loads(line)
    assert set(data["values"]) == set(data["sigma"]) >= {"driver_left.gain"} and data["out"] == str(
        tmp_path / "b.yaml"
    )


def test_the_summary_lists_each_feature_against_its_target():
    from amr_twin.calibration.fit import Fit

    fit = Fit(
        values={"driver_left.gain": 1.61},
        sigma={"driver_left.gain": 0.14},
        correlation={"driver_left.gain": {"driver_left.gain": 1}},
        residual=19.05,
        evaluations=40,
        target="the thesis",
        features=[
            {
                "name": "run2.right.overshoot",
                "twin": 1.45,
                "target": 4.0,
                "sigma": 1.0,
                "unit": "RPM",
                "weighted": -2.55,
            },
            {
                "name": "run3.left.true_delay",
                "twin": None,
                "target": 0.2,
                "sigma": 0.15,
                "unit": "s",
                "weighted": 10.0,
            },
        ],
    )
    lines = fit.text_lines()
    assert lines[0] == "calibrated against the thesis: chi^2 19.05 over 2 targets, 40 evaluations"
    assert next(x for x in lines if x.startswith("run2.right.overshoot")).split() == [
        "run2.right.overshoot",
        "1.45",
        "4",
        "1",
        "RPM",
        "-2.55",
    ]
    assert next(x for x in lines if x.startswith("run3.left.true_delay")).split()[1] == "missing"
    assert "correlated (|r| >= 0.9): none" in lines
