"""The spread section's markdown (experiments/chapter5/spread_report.py): the draws whose timestep
the tyres' guard halved."""

from amr_twin.experiments.chapter5.spread_report import markdown

BASE = {
    "samples": 2,
    "sampler": "lhs",
    "seed": 0,
    "parameters": ["wheel.tyre_loss_time_s"],
    "level": 0.9,
    "noise_level_rho": 0.5,
    "metrics": [],
    "duty_raised": [],
    "oscillation_more": [],
    "clipped": {},
    "draw_checks": [],
    "checks_passed": {},
}


def test_halved_draws_are_named_and_nothing_said_without():
    assert not any("halved" in line for line in markdown({**BASE, "tyre_timestep_halved": []}))
    halved = [{"draw": 1, "run": 8, "timestep_s": 0.0005, "stability_limit": 1.5}]
    lines = [
        line for line in markdown({**BASE, "tyre_timestep_halved": halved}) if "halved" in line
    ]
    assert lines == [
        "Physics timestep halved by the tyres' guard (stability number S > 1.5, "
        "docs/explanation/tyres.md) in "
        "draw 1 run 8 (0.5 ms)."
    ]


def test_the_draws_scorecards_are_summed_up_in_one_line():
    cards = [
        {"draw": 0, "checks": 88, "passed": 15, "true_checks": 84, "true_passed": 30},
        {"draw": 1, "checks": 88, "passed": 21, "true_checks": 84, "true_passed": 36},
    ]
    checks = {
        "published": {"median": 18.0, "low": 15.0, "high": 21.0, "n": 2},
        "true": {"median": 33.0, "low": 30.0, "high": 36.0, "n": 2},
    }
    lines = [
        line
        for line in markdown({**BASE, "draw_checks": cards, "checks_passed": checks})
        if line.startswith("Checks passed over the draws")
    ]
    assert len(lines) == 1
    assert (
        "published samples median 18 (15 – 21) of 88, true speed median 33 (30 – 36) of 84"
        in lines[0]
    )
