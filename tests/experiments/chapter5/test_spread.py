"""chapter5 --samples: the runs again over parameter draws, each banded metric beside the thesis
with its spread, the true-speed band in the plots; the nominal results are those without samples."""

import json

import numpy as np
from typer.testing import CliRunner

from amr_twin.cli.main import app

ARGS = [
    "experiment",
    "chapter5",
    "--runs",
    "1",
    "--duration-s",
    "3",
    "--jobs",
    "1",
    "--no-progress",
]


def test_chapter5_samples_report_the_spread_beside_the_thesis(tmp_path):
    plain = CliRunner().invoke(app, ARGS + ["--out", str(tmp_path / "plain")])
    drawn = CliRunner().invoke(
        app, ARGS + ["--out", str(tmp_path / "drawn"), "--samples", "3", "--seed", "2"]
    )
    assert plain.exit_code == 0 and drawn.exit_code == 0, drawn.output
    assert "over 3 parameter draws" in drawn.output
    a = json.loads((tmp_path / "plain" / "metrics.json").read_text())
    b = json.loads((tmp_path / "drawn" / "metrics.json").read_text())
    strip = lambda d: [{k: v for k, v in r.items() if k != "wall_s"} for r in d["runs"]]  # noqa: E731
    assert strip(a) == strip(b)  # the nominal runs are untouched by the draws
    spread = b["spread"]
    assert (
        spread["samples"] == 3
        and spread["seed"] == 2
        and "driver_left.gain" in spread["parameters"]
    )
    assert (
        spread["tyre_timestep_halved"] == []
    )  # draws near the nominal tyre: S far below the guard's limit
    banded = [m for m in spread["metrics"] if "thesis" in m]
    assert {m["metric"] for m in banded} == {
        "delay_s",
        "rise_s",
        "peak_s",
        "settling_s",
        "overshoot",
        "steady_error",
    }
    assert all(
        m["source"] == "published" and 0 <= m["in_band"] <= 3 and len(m["drivers"]) <= 3
        for m in banded
    )
    rise = next(m for m in spread["metrics"] if (m["source"], m["metric"]) == ("true", "rise_s"))
    assert (
        rise["low"] < rise["high"] and rise["low"] <= rise["median"] <= rise["high"]
    )  # the draws move it
    assert rise["nominal"] == a["runs"][0]["wheels"]["left"]["true"]["rise_s"]
    report = (tmp_path / "drawn" / "report.md").read_text()
    assert (
        "## Spread over the parameters' uncertainty" in report
        and "| 1 | left | overshoot | 2.0 | 0.0 – 3.0 |" in report
    )
    assert (tmp_path / "drawn" / "run1.png").stat().st_size > (
        tmp_path / "plain" / "run1.png"
    ).stat().st_size


def test_true_speed_bands_bracket_the_median():
    from amr_twin.model.config import load_config
    from amr_twin.experiments.chapter5 import spread as chapter5_spread
    from amr_twin.calibration.uncertainty import ParameterSpace

    draws = ParameterSpace.load().draw(3, seed=0, include=("driver_left.gain",))
    out = chapter5_spread.run(load_config(), draws, runs=[2], duration_s=2.0, progress=False)
    band = out["bands"][2]["right"]
    assert len(band["low"]) == len(out["bands"][2]["t_s"])
    assert np.all(band["low"] <= band["median"] + 1e-9) and np.all(
        band["median"] <= band["high"] + 1e-9
    )
    assert (
        np.max(band["high"] - band["low"]) > 1.0
    )  # the drawn gains and Ke spread the speed by RPMs


def test_each_draws_scorecard_is_the_nominal_one_of_its_parameters():
    """``draw_checks``: draw i's counts are what the nominal experiment scores with draw i's
    parameters, so two spreads of the same seed (e.g. with and without the tyres) compare draw
    by draw; the draws do move the scorecard."""
    from amr_twin.model.config import load_config
    from amr_twin.experiments.chapter5 import experiment as chapter5, spread as chapter5_spread
    from amr_twin.experiments.chapter5.criteria import count_checks
    from amr_twin.calibration.uncertainty import ParameterSpace

    cfg, runs = load_config(), [3, 4]  # near their dead-zone edges: the draws' scorecards differ
    draws = ParameterSpace.load().draw(
        4, seed=1, include=("driver_left.gain", "motor_left.ke_v_s_rad")
    )
    spread = chapter5_spread.run(cfg, draws, runs=runs, duration_s=4.0, progress=False)
    summary = chapter5_spread.summarise(
        chapter5.run(cfg, runs=runs, duration_s=4.0, progress=False), spread
    )
    cards = [
        (d["draw"], d["checks"], d["passed"], d["true_checks"], d["true_passed"])
        for d in summary["draw_checks"]
    ]
    for i in range(len(draws)):
        own = chapter5.run(draws.config(cfg, i), runs=runs, duration_s=4.0, progress=False)
        assert cards[i] == (i, *count_checks(own["runs"], own["comparisons"]))
    true = [c[4] for c in cards]
    assert (
        summary["checks_passed"]["true"]["low"]
        == min(true)
        < max(true)
        == summary["checks_passed"]["true"]["high"]
    )
