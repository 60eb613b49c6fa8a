"""Payload sweep: a tiny sweep, resume after an interruption, invalid positions, parsing."""

import csv
import json

import pytest
from typer.testing import CliRunner

from amr_twin.cli import app
from amr_twin.config import load_config
from amr_twin.experiments import payload_sweep as ps
from amr_twin.experiments import payload_sweep_report as report

DURATION_S = 2.0


@pytest.fixture(scope="module")
def cfg():
    return load_config()


def test_tiny_sweep_then_resume(cfg, tmp_path):
    args = dict(masses=[0.0, 20.0], positions=["center"], commands=["linear:0.7"], duration_s=DURATION_S,
                progress=False)
    # an interrupted earlier run left the 20 kg point done: its file must be reused, not redone
    done = ps.Point(20.0, "center", "linear:0.7", DURATION_S, "faithful", cfg)
    marker = {"key": done.key, "fingerprint": done.fingerprint, "mass_kg": 20.0, "position": "center",
              "command": "linear:0.7", "valid": True, "error": "", "safe": True, "marker": "kept"}
    (tmp_path / "runs").mkdir()
    (tmp_path / "runs" / f"{done.key}.json").write_text(json.dumps(marker))
    # a file from other parameters (stale fingerprint) is redone
    stale = ps.Point(0.0, "center", "linear:0.7", DURATION_S, "faithful", cfg)
    (tmp_path / "runs" / f"{stale.key}.json").write_text(json.dumps({**marker, "fingerprint": "old"}))

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

    report.plot(results, tmp_path)
    summary = report.report(results, tmp_path)
    assert summary["center"]["highest_safe_kg"] in (0.0, 20.0)
    with open(tmp_path / "sweep.csv") as fh:
        assert len(list(csv.DictReader(fh))) == 2
    assert (tmp_path / "sweep_linear_0.7.png").exists() and (tmp_path / "summary.md").exists()


def test_off_deck_position_is_invalid(cfg):
    row = ps.simulate_point(ps.Point(10.0, "0.5:0", "linear:0.7", DURATION_S, "faithful", cfg))
    assert row["valid"] is False and row["safe"] is False and "outside the deck" in row["error"]
    assert "invalid position" in report.unsafe_reason(row)


def test_named_positions_lie_on_the_deck(cfg):
    for name in ps.POSITIONS:
        x, y = ps.position_xy_m(cfg, name)
        ps.with_payload(cfg, 20.0, (x, y))  # raises ConfigError if off the deck
    assert ps.position_xy_m(cfg, "front-left-corner") == (pytest.approx(0.2), pytest.approx(0.075))


def test_parsing():
    assert ps.parse_masses("0:60:20") == [0, 20, 40, 60]
    assert ps.parse_masses("5,10") == [5, 10]
    for bad in ("0:60:0", "a", "-5", "nan"):
        with pytest.raises(ValueError):
            ps.parse_masses(bad)
    assert ps.parse_command("angular:60:-1").icc_m == -1.0
    assert ps.parse_command("motor:right:-1").direction == "backward"
    with pytest.raises(ValueError):
        ps.parse_command("spin:3")


def test_cli_dask_not_available(tmp_path):
    result = CliRunner().invoke(app, ["sweep", "payload", "--out", str(tmp_path / "s"), "--executor", "dask"])
    assert result.exit_code == 2 and "dask" in result.output
    assert not (tmp_path / "s").exists()


def test_per_wheel_panels_read_the_wheel_columns():
    from amr_twin.experiments.payload_sweep_report import _value
    row = {"left_reference_rpm": 53.5, "right_reference_rpm": 53.5, "left_delay_s": 0.9, "right_delay_s": 1.2,
           "left_steady_error_rpm": -3.0, "right_steady_error_rpm": 1.0}
    assert _value(row, "~delay_s") == 1.2
    assert _value(row, "~steady_error_rpm") == 3.0


def test_a_motor_over_the_drivers_continuous_rating_is_unsafe():
    """The same point, once with the shipped rating (11.1 A) and once with a rating the
    motors exceed while driving (0.6 A): only the second is unsafe, with the reason."""
    from amr_twin.experiments.payload_sweep_report import unsafe_reason

    low = load_config(sets=["driver.continuous_current_a=0.6"])
    ok = ps.simulate_point(ps.Point(0.0, "center", "linear:0.7", DURATION_S, "faithful", load_config()))
    over = ps.simulate_point(ps.Point(0.0, "center", "linear:0.7", DURATION_S, "faithful", low))
    assert ok["safe"] and not ok["motor_overload"]
    assert 0.6 < max(over["left_steady_current_a"], over["right_steady_current_a"]) < 11.1
    assert not over["safe"] and over["motor_overload"] and "motor overload" in unsafe_reason(over)
