"""The spread section's markdown (experiments/chapter5_spread_report.py): the draws whose timestep the tyres' guard halved."""

from amr_twin.experiments.chapter5_spread_report import markdown

BASE = {"samples": 2, "sampler": "lhs", "seed": 0, "parameters": ["wheel.tyre_loss_time_s"], "level": 0.9,
        "noise_level_rho": 0.5, "metrics": [], "duty_raised": [], "oscillation_more": [], "clipped": {}}


def test_halved_draws_are_named_and_nothing_said_without():
    assert not any("halved" in line for line in markdown({**BASE, "tyre_timestep_halved": []}))
    halved = [{"draw": 1, "run": 8, "timestep_s": 0.0005, "stability_limit": 1.5}]
    lines = [line for line in markdown({**BASE, "tyre_timestep_halved": halved}) if "halved" in line]
    assert lines == ["Physics timestep halved by the tyres' guard (stability number S > 1.5, docs/tyres.md) in "
                     "draw 1 run 8 (0.5 ms)."]
