"""Calibration against a log of wheel speeds recovers a known plant parameter."""

import csv

import pytest

from amr_twin.calibration import calibrate, parse_command, read_log, write_params
from amr_twin.config import load_config
from amr_twin.loop import TwinOptions
from amr_twin.run import run_command


def _write_log(path, gain):
    cfg = load_config(sets=[f"driver.gain={gain}"])
    series = run_command(cfg, parse_command("motor:left:forward:1.0"), 6.0, TwinOptions(world="empty")).series
    with open(path, "w", newline="") as fh:
        out = csv.writer(fh)
        out.writerow(["t_s", "wheel", "rpm", "command"])
        for t, rpm in series.published[0]:
            out.writerow([f"{t:.6f}", "left", f"{rpm:.4f}", "motor:left:forward:1.0"])


def test_fit_recovers_driver_gain_from_a_log(tmp_path):
    log = tmp_path / "real.csv"
    _write_log(log, gain=1.55)
    fit = calibrate(str(log), base_sets=["driver.gain=1.9"], max_evaluations=14,
                    parameters={"driver.gain": (1.0, 3.0)})
    assert abs(fit.values["driver.gain"] - 1.55) < abs(1.9 - 1.55) / 3
    assert fit.residual < 4.0  # RPM^2: RMS under 2 RPM, half the firmware's 4 RPM dead band
    out = tmp_path / "params.yaml"
    write_params(fit, out)
    cfg = load_config(override_file=out)
    assert cfg.driver.gain == pytest.approx(fit.values["driver.gain"], abs=1e-4)


def test_log_format_errors_name_the_problem(tmp_path):
    bad = tmp_path / "bad.csv"
    bad.write_text("t_s,wheel,rpm\n0.1,left,3\n")
    with pytest.raises(ValueError, match="missing column"):
        read_log(bad)
    with pytest.raises(ValueError, match="expected linear"):
        parse_command("fly:3")
