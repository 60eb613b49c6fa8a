"""Payload sweep: a tiny sweep, resume after an interruption, invalid positions, parsing."""

import csv
import json

import pytest
from typer.testing import CliRunner

from amr_twin.cli.main import app
from amr_twin.model.config import load_config
from amr_twin.experiments.payload import sweep as ps
from amr_twin.experiments.payload.point import Point
from amr_twin.experiments.payload.simulation import simulate_point
from amr_twin.experiments.payload import sweep_report as report

DURATION_S = 2.0


@pytest.fixture(scope="module")
def cfg():
    return load_config()


def test_tiny_sweep_then_resume(cfg, tmp_path):
    args = dict(
        masses=[0.0, 20.0],
        positions=["center"],
        commands=["linear:0.7"],
        duration_s=DURATION_S,
        progress=False,
    )
    # an interrupted earlier run left the 20 kg point done: its file must be reused, not redone
    done = Point(20.0, "center", "linear:0.7", DURATION_S, "faithful", cfg)
    marker = {
        "key": done.key,
        "fingerprint": done.fingerprint,
        "mass_kg": 20.0,
        "position": "center",
        "command": "linear:0.7",
        "valid": True,
        "error": "",
        "safe": True,
        "marker": "kept",
    }
    (tmp_path / "runs").mkdir()
    (tmp_path / "runs" / f"{done.key}.json").write_text(json.dumps(marker))
    # a file from other parameters (stale fingerprint) is redone
    stale = Point(0.0, "center", "linear:0.7", DURATION_S, "faithful", cfg)
    (tmp_path / "runs" / f"{stale.key}.json").write_text(
        json.dumps({**marker, "fingerprint": "old"})
    )

    results = ps.run(cfg, tmp_path, **args)
    assert (results["simulated"], results["reused"]) == (1, 1)
    rows = {r["mass_kg"]: r for r in results["rows"]}
    assert rows[20.0]["marker"] == "kept"
    fresh = rows[0.0]
    assert fresh["valid"] and not fresh["error"] and fresh["fingerprint"] == stale.fingerprint
    assert fresh["left_reference_rpm"] == pytest.approx(53.47, abs=0.01)
    assert 0.0 < fresh["left_steady_duty"] < 1.0 and fresh["max_tilt_deg"] < 5.0
    assert fresh["static_tip_margin_m"] > 0 and fresh["dyn_min_wheel_n"] > 0

    again = ps.run(cfg, tmp_path, **args)
    assert (again["simulated"], again["reused"]) == (0, 2)
    shorter = ps.run(cfg, tmp_path, **{**args, "duration_s": 0.5, "masses": [0.0]})
    assert (shorter["simulated"], shorter["reused"]) == (
        1,
        0,
    )  # another duration: redone, not reused
    assert shorter["rows"][0]["fingerprint"] != fresh["fingerprint"]

    report.plot(results, tmp_path)
    summary = report.report(results, tmp_path)
    assert summary["center"]["highest_safe_kg"] in (0.0, 20.0)
    with open(tmp_path / "sweep.csv") as fh:
        assert len(list(csv.DictReader(fh))) == 2
    assert (tmp_path / "sweep_linear_0.7.png").exists() and (tmp_path / "summary.md").exists()


def test_cli_dask_not_available(tmp_path):
    result = CliRunner().invoke(
        app, ["sweep", "payload", "--out", str(tmp_path / "s"), "--executor", "dask"]
    )
    assert result.exit_code == 2 and "dask" in result.output
    assert not (tmp_path / "s").exists()


def test_per_wheel_panels_read_the_wheel_columns():
    from amr_twin.experiments.payload.rows import column_value

    row = {
        "left_reference_rpm": 53.5,
        "right_reference_rpm": 53.5,
        "left_delay_s": 0.9,
        "right_delay_s": 1.2,
        "left_steady_error_rpm": -3.0,
        "right_steady_error_rpm": 1.0,
    }
    assert column_value(row, "~delay_s") == 1.2
    assert column_value(row, "~steady_error_rpm") == 3.0


def _without_wall(text: str) -> str:
    """A CSV or JSON text without its wall-time fields (the only ones not simulated)."""
    if text.lstrip().startswith("{"):
        data = json.loads(text)
        data.pop("wall_s", None)
        return json.dumps(data, sort_keys=True)
    rows = list(csv.reader(text.splitlines()))
    drop = rows[0].index("wall_s")
    return "\n".join(",".join(c for i, c in enumerate(r) if i != drop) for r in rows)


def test_one_sample_is_the_plain_sweep(tmp_path):
    args = [
        "sweep",
        "payload",
        "--masses",
        "0,20",
        "--positions",
        "center",
        "--commands",
        "linear:0.7",
        "--duration-s",
        str(DURATION_S),
        "--jobs",
        "1",
        "--no-progress",
    ]
    plain = CliRunner().invoke(app, args + ["--out", str(tmp_path / "plain")])
    one = CliRunner().invoke(app, args + ["--out", str(tmp_path / "one"), "--samples", "1"])
    assert plain.exit_code == 0 and one.exit_code == 0, one.output
    for name in ("sweep.csv", "summary.json"):
        assert _without_wall((tmp_path / "one" / name).read_text()) == _without_wall(
            (tmp_path / "plain" / name).read_text()
        )
    assert sorted(p.name for p in (tmp_path / "one").iterdir()) == sorted(
        p.name for p in (tmp_path / "plain").iterdir()
    )


def test_samples_run_resume_and_report(cfg, tmp_path):
    from amr_twin.experiments.payload import spread_report
    from amr_twin.calibration.uncertainty import ParameterSpace

    space = ParameterSpace.load()
    args = dict(
        masses=[0.0, 20.0],
        positions=["center"],
        commands=["linear:0.7"],
        duration_s=DURATION_S,
        progress=False,
    )
    draws = space.draw(2, seed=0)
    results = ps.run(cfg, tmp_path, draws=draws, **args)
    assert (results["simulated"], results["reused"]) == (6, 0)
    nominal = [r for r in results["rows"] if "sample" not in r]
    plain = ps.run(cfg, tmp_path / "plain", **args)["rows"]
    assert [{k: v for k, v in r.items() if k != "wall_s"} for r in nominal] == [
        {k: v for k, v in r.items() if k != "wall_s"} for r in plain
    ]
    drawn = [r for r in results["rows"] if "sample" in r]
    assert sorted({r["sample"] for r in drawn}) == [0, 1]
    assert all(r["key"].endswith(f"_s{r['sample']}_{draws.sample_id(r['sample'])}") for r in drawn)
    loads = [r["dyn_min_wheel_n"] for r in results["rows"] if r["mass_kg"] == 0.0]
    assert len({round(v, 6) for v in loads}) == 3  # nominal and both draws differ
    again = ps.run(cfg, tmp_path, draws=draws, **args)
    assert (again["simulated"], again["reused"]) == (0, 6)
    from amr_twin.experiments.payload.rows import rows_csv

    assert rows_csv(again["rows"]) == rows_csv(
        results["rows"]
    )  # read back from the files: the same CSV as fresh
    other = ps.run(cfg, tmp_path, draws=space.draw(2, seed=1), **args)
    assert (other["simulated"], other["reused"]) == (4, 2)  # new draws, same nominal runs

    spread_report.analyse(results)
    spread_report.plot(results, tmp_path)
    summary = spread_report.report(results, tmp_path)
    for name in (
        "sweep.csv",
        "samples.csv",
        "intervals.csv",
        "sensitivity.csv",
        "summary.md",
        "sweep_linear_0.7.png",
        "sensitivity.png",
    ):
        assert (tmp_path / name).stat().st_size > 0, name
    with open(tmp_path / "intervals.csv") as fh:
        entries = [r for r in csv.DictReader(fh) if r["n"] == "2"]
    assert entries and all(
        float(r["low"]) <= float(r["median"]) <= float(r["high"]) for r in entries
    )
    assert (
        summary["samples"]["n"] == 2 and summary["answers"]["center"]["highest_safe_kg"]["n"] == 2
    )
    assert "90% interval" in (tmp_path / "summary.md").read_text()


@pytest.mark.parametrize(
    "extra, words",
    [
        (["--seed", "3"], "--seed: only used with --samples N"),
        (["--samples", "3", "--sampler", "sobol"], "power of 2"),
        (["--samples", "0"], "--samples 0: must be in 1..4096"),
        (
            ["--samples", "4096", "--masses", "0:60:10"],
            "(--samples + 1): 28679 runs; at most 10000",
        ),
        (
            ["--samples", "2", "--calibration", "nowhere.yaml"],
            "--calibration nowhere.yaml: no such file",
        ),
    ],
)
def test_sample_options_are_checked_before_the_work(tmp_path, extra, words):
    result = CliRunner().invoke(
        app,
        [
            "sweep",
            "payload",
            "--out",
            str(tmp_path / "s"),
            "--positions",
            "center",
            "--commands",
            "linear:0.7",
            *extra,
        ],
    )
    assert result.exit_code == 2 and words in result.output, result.output
    assert not (tmp_path / "s").exists()


def test_lift_off_is_judged_on_the_springs_not_on_contact_chatter():
    """The rigid contact (the brush tyres' normal-only contact does not chatter: 25 N at least
    here), balls 1 mm low: the empty robot's inner wheel carries about 16 N in the clockwise turn
    and its stiff contact chatters (0 N in some steps); the tyre stays compressed, so the wheel has
    not lifted. Balls 2 mm low: the tyre spring goes slack, a real lift-off."""
    rows = {}
    for drop in (0.001, 0.002):
        cfg = load_config(sets=[f"caster.drop_m={drop}", "wheel.tyre_slip=false"])
        rows[drop] = simulate_point(
            Point(0.0, "center", "angular:-60:-1", 2.5, "faithful", cfg)
        ).as_json()
    chatter, lifted = rows[0.001], rows[0.002]
    assert chatter["dyn_min_wheel_contact_n"] < 0.5 < 5.0 < chatter["dyn_min_wheel_n"]
    assert not chatter["wheel_lift_off"] and chatter["safe"]
    assert lifted["wheel_lift_off"] and "wheel_right" in lifted["dyn_lifted"] and not lifted["safe"]


def test_a_payloads_commands_are_one_work_item(cfg):
    """Each payload's commands run in one process (its second twin starts from the first's settled
    physics); a sweep with fewer payloads than processes keeps one point per item (stays parallel);
    drawn configurations are never merged with the nominal one."""
    commands = ["linear:0.7", "angular:60:-1"]
    points = [
        Point(m, p, c, 1.0, "faithful", cfg)
        for m in (0.0, 20.0)
        for p in ("center", "rear")
        for c in commands
    ]
    groups = ps.by_payload(points, jobs=2)
    assert [len(g) for g in groups] == [2, 2, 2, 2]
    for g in groups:
        assert len({(p.mass_kg, p.position) for p in g}) == 1 and [p.command for p in g] == commands
    assert [p for g in groups for p in g] == points
    assert ps.by_payload(points, jobs=5) == [(p,) for p in points]
    drawn = cfg.model_copy()
    mixed = [
        points[0],
        Point(0.0, "center", "angular:60:-1", 1.0, "faithful", drawn, sample=0, sample_id="x"),
    ]
    assert ps.by_payload(mixed) == [(mixed[0],), (mixed[1],)]


def test_a_parallel_sweep_gives_the_rows_of_a_serial_one(cfg, tmp_path):
    args = dict(
        masses=[0.0, 20.0],
        positions=["center"],
        commands=["linear:0.7", "angular:60:-1"],
        duration_s=1.0,
        progress=False,
    )
    rows = {
        jobs: ps.run(cfg, tmp_path / f"jobs{jobs}", jobs=jobs, **args)["rows"] for jobs in (1, 2)
    }
    for r in (*rows[1], *rows[2]):
        r.pop("wall_s", None)
    keys = [
        Point(m, "center", c, 1.0, "faithful", cfg).key
        for m in args["masses"]
        for c in args["commands"]
    ]
    assert [r["key"] for r in rows[1]] == [r["key"] for r in rows[2]] == keys
    assert all(
        json.loads((tmp_path / "jobs2" / "runs" / f"{k}.json").read_text())["key"] == k
        for k in keys
    )
    assert json.dumps(rows[2], sort_keys=True) == json.dumps(rows[1], sort_keys=True)
