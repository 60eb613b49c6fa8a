"""``amr-twin sweep payload`` (amr_twin/cli/sweep.py): recordings per point, resuming, bounds,
repeated values.

The recordings are read back with rerun's own reader; the rows must be the same with and without
recording."""

import json

import pytest
from typer.testing import CliRunner

from amr_twin.cli.main import app
from amr_twin.experiments.payload import sweep as ps
from amr_twin.experiments.payload.point import Point
from amr_twin.model.config import load_config
from test_cli_experiment import _without_wall, rrd_summary

SWEEP = dict(masses=[0.0, 20.0], positions=["center"], commands=["linear:0.7"], duration_s=1.0)
SWEEP_ARGS = [
    "--masses",
    "0,20",
    "--positions",
    "center",
    "--commands",
    "linear:0.7",
    "--duration-s",
    "1",
    "--no-progress",
]


@pytest.fixture(scope="module")
def cfg():
    return load_config()


def test_sweep_records_each_point_and_resume_does_not_redo(cfg, tmp_path):
    rec, out = tmp_path / "rec", tmp_path / "out"
    res = CliRunner().invoke(
        app,
        ["sweep", "payload", "--out", str(out), "--jobs", "2", "--record", str(rec), *SWEEP_ARGS],
    )
    assert res.exit_code == 0, res.output
    keys = sorted(
        Point(m, "center", "linear:0.7", 1.0, "faithful", cfg).key for m in SWEEP["masses"]
    )
    assert sorted(p.name for p in rec.iterdir()) == [f"{k}.rrd" for k in keys]
    for key in keys:
        rows, last_ns = rrd_summary(rec / f"{key}.rrd")
        assert last_ns == pytest.approx(1e9, abs=1e6)
        assert (
            rows["/wheels/right/true_rpm"] == 101 and rows["/commands"] == 2
        )  # client call + wheel_Command
    assert "2 points recorded" in res.output
    # the rows are those of a sweep without recording
    plain = ps.run(cfg, tmp_path / "plain", progress=False, **SWEEP)
    recorded = [json.loads((out / "runs" / f"{k}.json").read_text()) for k in keys]
    assert _without_wall(recorded) == _without_wall(sorted(plain["rows"], key=lambda r: r["key"]))
    # resumed: a missing recording does not make a finished point simulate again
    (rec / f"{keys[0]}.rrd").unlink()
    kept = (rec / f"{keys[1]}.rrd").stat().st_mtime_ns
    res = CliRunner().invoke(
        app, ["sweep", "payload", "--out", str(out), "--record", str(rec), *SWEEP_ARGS]
    )
    assert res.exit_code == 0, res.output
    assert "0 simulated, 2 reused" in res.output and "not re-simulated" in res.output
    assert [p.name for p in rec.iterdir()] == [f"{keys[1]}.rrd"]
    assert (rec / f"{keys[1]}.rrd").stat().st_mtime_ns == kept


def test_sweep_interrupted_while_recording_leaves_nothing_half_written(cfg, tmp_path, monkeypatch):
    import amr_twin.recording.rerun_log as rerun_log

    def interrupt(*_args, **_kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(rerun_log, "_log_trajectory", interrupt)  # the last stream of the .rrd
    with pytest.raises(KeyboardInterrupt):
        ps.run(
            cfg,
            tmp_path / "out",
            progress=False,
            record_dir=tmp_path / "rec",
            mcap_dir=tmp_path / "rec",
            **dict(SWEEP, masses=[0.0]),
        )
    assert list((tmp_path / "rec").iterdir()) == []  # neither the recording nor its temporary
    assert not (tmp_path / "out" / "runs").exists() or not list(
        (tmp_path / "out" / "runs").iterdir()
    )


def test_sweep_sizes_are_bounded_before_any_work(tmp_path):
    out = tmp_path / "s"
    for args, text in (
        (["--masses", "0:60:1e-9"], "6e+10 masses; at most 1000"),
        (
            [
                "--masses",
                "0:199.5:0.5",
                "--positions",
                "center,front,rear,left,right,0.1:0",
                "--commands",
                "linear:0.7,linear:0.5,linear:0.3,angular:60:-1,stop",
            ],
            "12000 points; at most 10000",
        ),
        (["--duration-s", "1e9"], "--duration-s 1e+09: must be in [0.1, 3600] s"),
    ):
        res = CliRunner().invoke(app, ["sweep", "payload", "--out", str(out), *args])
        assert res.exit_code == 2 and text in res.stderr, res.stderr
        assert len(res.stderr.strip().splitlines()) == 1 and not out.exists()


def test_repeated_sweep_values_are_simulated_once(tmp_path):
    res = CliRunner().invoke(
        app,
        [
            "sweep",
            "payload",
            "--out",
            str(tmp_path),
            "--masses",
            "0,0.0",
            "--positions",
            "center,0:0",
            "--commands",
            "linear:0.7,linear:0.70",
            "--duration-s",
            "1",
            "--jobs",
            "1",
            "--no-progress",
        ],
    )
    assert res.exit_code == 0, res.output
    assert (
        "1 points: 1 simulated" in res.stdout
        and "simulated once: 0.0, 0:0, linear:0.70" in res.stderr
    )
    assert len(list((tmp_path / "runs").iterdir())) == 1
