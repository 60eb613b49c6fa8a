"""amr-twin bench: the figures the README quotes are all there and consistent (not timed)."""

import pytest

from amr_twin.benchmark import run_benchmarks
from amr_twin.config import load_config

README_KEYS = ("physics_us_per_step", "twin_s_per_sim_s", "bare_physics_s_per_sim_s", "ratio",
               "sensors_ratio", "lidar_scan_us", "lidar_scan_one_call_us")


def test_figures_are_present_and_each_ratio_is_against_bare_physics():
    r = run_benchmarks(load_config(), sim_s=0.2)
    assert all(r[k] > 0 for k in README_KEYS), r
    assert r["ratio"] == pytest.approx(r["twin_s_per_sim_s"] / r["bare_physics_s_per_sim_s"], rel=0.02)
    assert r["lidar_beams_per_scan"] == 364 and r["timer"] == "process_time"
    assert "avr_skipped" in r or (r["avr_ratio"] > 1 and r["avr_realtime_factor"] > 0)  # --firmware avr


@pytest.mark.parametrize("args, text", [(["--jobs", "0"], "--jobs 0"), (["--sim-s", "-1"], "--sim-s -1")])
def test_bench_refuses_bad_options_in_one_line(args, text):
    from typer.testing import CliRunner

    from amr_twin.cli import app

    res = CliRunner().invoke(app, ["bench", *args])
    assert res.exit_code == 2 and text in res.output and len(res.output.strip().splitlines()) == 1
