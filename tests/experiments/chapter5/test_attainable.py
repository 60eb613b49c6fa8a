"""Which chapter 5 findings a plant inside the ranges meets: the draws, the verdicts, the pairs, the
command."""

from __future__ import annotations

import json

import pytest
from typer.testing import CliRunner

from amr_twin.cli.main import app
from amr_twin.experiments.chapter5 import attainable as att
from amr_twin.model.config import load_config, load_parameters


@pytest.fixture(scope="module")
def cfg():
    return load_config()


def test_draws_are_seeded_and_inside_the_sourced_ranges(cfg):
    a, b, c = att.draw_values(cfg, 40, 3), att.draw_values(cfg, 40, 3), att.draw_values(cfg, 40, 4)
    assert a == b and a != c
    _, meta = load_parameters()
    for key in att.RANGED:
        lo, hi = meta[key]["range"]
        values = [d[key] for d in a]
        assert (
            lo <= min(values) and max(values) <= hi and max(values) - min(values) > 0.5 * (hi - lo)
        )
    gains = [d["driver_right.gain"] / cfg.driver_left.gain for d in a]
    assert (
        1 - att.BOARD_TOLERANCE <= min(gains) < 0.98
        and 1.02 < max(gains) <= 1 + att.BOARD_TOLERANCE
    )
    with pytest.raises(ValueError, match="samples 0: must be in 1..512"):
        att.draw_values(cfg, 0, 1)


def _data(verdicts: dict[str, bool], right: float, left: float, raised: list[bool]) -> dict:
    return {
        "findings": {
            "findings": [
                {"key": k, "verdict": "reproduced" if v else "not reproduced"}
                for k, v in verdicts.items()
            ]
            + [{"key": "timings", "verdict": "reproduced"}]
        },
        "runs": [
            {
                "run": 1,
                "payload_kg": 0,
                "wheels": {"left": {"published": {"overshoot": left, "steady_error": -1.5}}},
            },
            {
                "run": 2,
                "payload_kg": 0,
                "wheels": {"right": {"published": {"overshoot": right, "steady_error": 4.5}}},
            },
            {
                "run": 7,
                "payload_kg": 20,
                "wheels": {"right": {"published": {"overshoot": 0, "steady_error": -9.0}}},
            },
        ],
        "payload_duty": [{"raised": r} for r in raised],
        "comparisons": [
            {"verdict": "pass", "true_verdict": "fail"},
            {"verdict": "pass", "true_verdict": "pass"},
        ],
    }


def test_judge_reads_each_finding_and_the_figures():
    holds = {"overshoot_right": True, "tracking": False, "duty_raised": False, "oscillation": True}
    d = att.judge(_data(holds, 3.5, 1.25, [True, False, True, True]), {"x": 1.0})
    assert d.holds == holds and d.overshoot_rpm == (3.5, 1.25) and d.raised_wheels == 3
    assert (
        d.oscillation_more == (2, 1) and d.worst_steady_error_rpm == 4.5
    )  # the loaded run is not counted


def test_summary_counts_findings_alone_and_in_pairs():
    def draw(o, t, du, os_=(1.0, 1.0), raised=0, more=(1, 0), worst=5.0):
        return att.Draw(
            {},
            {"overshoot_right": o, "tracking": t, "duty_raised": du, "oscillation": False},
            os_,
            raised,
            more,
            worst,
        )

    s = att.summary(
        [
            draw(True, True, False, (4.0, 1.0)),
            draw(True, False, True, raised=4, more=(3, 2)),
            draw(False, True, True, (2.0, 2.5), raised=2, more=(4, 1), worst=2.5),
        ]
    )
    assert s["held"] == {"overshoot_right": 2, "tracking": 2, "duty_raised": 2, "oscillation": 0}
    assert s["pairs"]["overshoot_right+tracking"] == 1 and s["pairs"]["tracking+duty_raised"] == 1
    assert (
        s["pairs"]["overshoot_right+duty_raised"] == 1
        and s["pairs"]["duty_raised+oscillation"] == 0
    )
    assert s["all"] == 0 and s["best_right_minus_left_rpm"] == 3.0 and s["most_raised_wheels"] == 4
    assert s["most_oscillating_more"] == 2 and s["least_worst_steady_error_rpm"] == 2.5
    assert any("overshoot_right and tracking: 1 of 3" in line for line in att.lines(s))


@pytest.mark.parametrize(
    "args, message",
    [
        (["--samples", "0"], "--samples 0: must be in 1..512"),
        (["--seed", "-1"], "--seed -1: must be >= 0"),
    ],
)
def test_bad_options_are_refused_in_one_line(args, message):
    res = CliRunner().invoke(app, ["experiment", "chapter5-attainable", *args])
    assert (
        res.exit_code == 2 and message in res.stderr and len(res.stderr.strip().splitlines()) == 1
    )


def test_the_command_writes_every_draw(tmp_path):
    out = tmp_path / "att.json"
    res = CliRunner().invoke(
        app,
        [
            "experiment",
            "chapter5-attainable",
            "--samples",
            "1",
            "--seed",
            "5",
            "--jobs",
            "1",
            "--out",
            str(out),
        ],
    )
    assert res.exit_code == 0, res.output
    data = json.loads(out.read_text())
    assert (
        data["samples"] == 1 and len(data["draws"]) == 1 and set(data["held"]) == set(att.FINDINGS)
    )
    assert data["draws"][0]["values"] == att.draw_values(load_config(), 1, 5)[0]
    assert "holds in" in res.stdout


def test_the_plant_key_ignores_the_drawn_values_and_sees_any_other(cfg):
    base = att.plant(cfg)
    assert (
        att.plant(load_config(sets=["wheel.rolling_resistance=0.021"]))["config_sha256"]
        == base["config_sha256"]
    )
    assert (
        att.plant(load_config(sets=["wheel.tyre_slip=false"]))["config_sha256"]
        != base["config_sha256"]
    )
    assert att.plant(load_config(sets=["driver_left.gain=1.7"]))["held"]["driver_left.gain"] == 1.7


def test_the_committed_study_is_of_the_shipped_plant_and_what_a_draw_gives_now(cfg):
    """Regenerate with python -m amr_twin.experiments.documents.figures after a change of the
    plant."""
    data = att.committed(cfg)
    assert data is not None, (
        f"{att.COMMITTED_JSON.name} was drawn around another plant: run doc_figures"
    )
    assert list(data["seeds"]) == [str(s) for s in att.COMMITTED_SEEDS]
    first = data["seeds"]["1"]["draws"][0]
    again = att.study(cfg, 1, 1, jobs=2)[0]
    assert (
        again.values == pytest.approx(first["values"], rel=1e-12) and again.holds == first["holds"]
    )
    assert again.overshoot_rpm == pytest.approx(first["overshoot_rpm"], abs=1e-6)
    assert att.committed(load_config(sets=["wheel.tyre_slip=false"])) is None


def test_the_report_quotes_the_study_or_says_it_does_not_apply():
    from amr_twin.experiments.chapter5.findings_section import attainable

    assert "drawn around another plant" in attainable({})[0]
    study = {
        "seeds": {
            "1": {
                "samples": 2,
                "held": {k: 0 for k in att.FINDINGS},
                "all": 0,
                "pairs": {"a+b": 0},
                "best_right_overshoot_rpm": 1.2,
                "best_right_minus_left_rpm": 0.3,
                "least_worst_steady_error_rpm": 2.5,
                "most_raised_wheels": 3,
                "most_oscillating_more": 1,
            }
        }
    }
    text = "\n".join(attainable({"attainable": study}))
    assert (
        "| 20 kg: the PI raises the duty on all 4 wheels of runs 7, 8 | 0 | 3 of 4 wheels at most |"
        in text
    )
