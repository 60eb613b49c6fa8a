"""Which of the thesis' chapter 5 findings a plant inside the sourced ranges can meet, and which
conflict.

:func:`study` draws plants uniformly (seeded) over the parameters that could make one wheel
overshoot more or a loaded wheel leave the PI's dead zone, each inside its range: the right board's
gain against the left's (:data:`BOARD_TOLERANCE`), each motor's winding resistance, the tyres' and
the balls' rolling resistance (their ``range`` in ``models/amr/amr.yaml``). Each draw runs the eight
runs (:func:`.experiment.run`) and is judged by :func:`.findings.findings`. :func:`summary` gives,
per finding, the draws where it holds and the best figure reached, and for each pair the draws where
both hold: a finding no draw meets is out of reach; a pair no draw meets conflicts.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass
from itertools import combinations

import numpy as np

from amr_twin.model.config import TwinConfig, load_parameters, with_values
from amr_twin.model.paths import ROOT

BOARD_TOLERANCE = 0.05
"""Right board's gain against the left's, +-: two ZS-X11D1 boards of one model differ by their 5 V
regulator (78L05 class, +-5 %) and input divider resistors (1-5 %), which scale the speed demand."""
RANGED = ("motor_left.resistance_ohm", "wheel.rolling_resistance", "caster.rolling_resistance")
FINDINGS = ("overshoot_right", "tracking", "duty_raised", "oscillation")
MAX_SAMPLES = 512
COMMITTED_JSON = ROOT / "experiments" / "chapter5" / "reference" / "attainable.json"
"""The study the documents and the chapter 5 report quote (``python -m
amr_twin.experiments.documents.figures``)."""
COMMITTED_SEEDS = (1, 2)
COMMITTED_SAMPLES = 64
HELD = (
    "driver_left.gain",
    "motor_left.ke_v_s_rad",
    "motor_right.ke_v_s_rad",
    "motor_left.friction_nm",
    "motor_right.friction_nm",
)
"""The calibrated values the drawn plants keep, named in the committed study (the whole
configuration but the drawn values is held to it by a hash)."""


@dataclass(frozen=True)
class Draw:
    """One drawn plant: its parameter values and each finding's verdict (True: reproduced)."""

    values: dict[str, float]
    holds: dict[str, bool]
    overshoot_rpm: tuple[float, float]  # runs 2 / 1: right and left published overshoot, RPM
    raised_wheels: int  # of the 4 wheels of runs 7 and 8
    oscillation_more: tuple[
        int, int
    ]  # 20 kg comparisons oscillating more: published, true speed (of 4)
    worst_steady_error_rpm: float  # largest |steady error| of an unloaded wheel, published, RPM


def ranges(cfg: TwinConfig) -> dict[str, tuple[float, float]]:
    """Each drawn parameter's bounds: the sourced ``range`` of :data:`RANGED`, the board
    tolerance."""
    _, meta = load_parameters()
    out = {key: tuple(meta[key]["range"]) for key in RANGED}
    out["motor_right.resistance_ohm"] = out[
        "motor_left.resistance_ohm"
    ]  # a unit of its own, same range
    left = cfg.driver_left.gain
    out["driver_right.gain"] = (left * (1 - BOARD_TOLERANCE), left * (1 + BOARD_TOLERANCE))
    return out


def draw_values(cfg: TwinConfig, samples: int, seed: int) -> list[dict[str, float]]:
    """``samples`` parameter sets, uniform inside :func:`ranges` (seeded: same seed, same sets)."""
    if not 1 <= samples <= MAX_SAMPLES:
        raise ValueError(f"samples {samples}: must be in 1..{MAX_SAMPLES}")
    bounds = ranges(cfg)
    rng = np.random.default_rng(seed)
    return [
        {k: float(rng.uniform(lo, hi)) for k, (lo, hi) in bounds.items()} for _ in range(samples)
    ]


def judge(data: dict, values: dict[str, float]) -> Draw:
    """The draw's verdicts from its ``metrics.json`` object ``data`` (with ``findings``)."""
    verdicts = {f["key"]: f["verdict"] == "reproduced" for f in data["findings"]["findings"]}
    runs = {r["run"]: r for r in data["runs"]}
    right = runs[2]["wheels"]["right"]["published"]["overshoot"]
    left = runs[1]["wheels"]["left"]["published"]["overshoot"]
    raised = sum(bool(c["raised"]) for c in data["payload_duty"])
    comparisons = data["comparisons"]
    more = (
        sum(c["verdict"] == "pass" for c in comparisons),
        sum(c["true_verdict"] == "pass" for c in comparisons),
    )
    worst = max(
        abs(w["published"]["steady_error"])
        for r in data["runs"]
        if r["payload_kg"] == 0
        for w in r["wheels"].values()
    )
    return Draw(values, {k: verdicts[k] for k in FINDINGS}, (right, left), raised, more, worst)


def study(cfg: TwinConfig, samples: int, seed: int, jobs: int = 1, progress=None) -> list[Draw]:
    """Run the eight runs for each drawn plant; ``progress(i, n)`` after each draw."""
    from amr_twin.experiments.chapter5.experiment import run
    from amr_twin.experiments.chapter5.metrics import metrics

    out = []
    all_values = draw_values(cfg, samples, seed)
    for i, values in enumerate(all_values):
        results = run(with_values(cfg, values), jobs=jobs, progress=False, study=False)
        out.append(judge(metrics(results).as_json(), values))
        if progress is not None:
            progress(i + 1, len(all_values))
    return out


def summary(draws: list[Draw]) -> dict:
    """Per finding: draws where it holds; per pair: draws where both hold; the best overshoot and
    duty."""
    held = {k: sum(d.holds[k] for d in draws) for k in FINDINGS}
    pairs = {
        f"{a}+{b}": sum(d.holds[a] and d.holds[b] for d in draws)
        for a, b in combinations(FINDINGS, 2)
    }
    gap = max(draws, key=lambda d: d.overshoot_rpm[0] - d.overshoot_rpm[1])
    return {
        "samples": len(draws),
        "held": held,
        "pairs": pairs,
        "all": sum(all(d.holds.values()) for d in draws),
        "best_right_minus_left_rpm": gap.overshoot_rpm[0] - gap.overshoot_rpm[1],
        "best_right_overshoot_rpm": max(d.overshoot_rpm[0] for d in draws),
        "most_raised_wheels": max(d.raised_wheels for d in draws),
        "most_oscillating_more": max(min(d.oscillation_more) for d in draws),
        "least_worst_steady_error_rpm": min(d.worst_steady_error_rpm for d in draws),
        "draws": [asdict(d) for d in draws],
    }


UNUSED_SECTIONS = ("navigation", "actors")
"""Sections of the parameter file no chapter 5 run reads (no navigation stack, no actors)."""

UNUSED_KEYS = ("battery.charge_current_a", "payload.max_mass_kg", "payload.handling_time_s")
"""Parameters no chapter 5 run reads: the charger, the deck's rating and the worker's handling
time (a fleet's pick, drop and charging)."""


def plant(cfg: TwinConfig) -> dict:
    """What a study's draws depend on besides the seed: a SHA-256 of the configuration without the
    drawn values and without what chapter 5's runs do not use (:data:`UNUSED_SECTIONS`,
    :data:`UNUSED_KEYS`), the calibrated values kept (:data:`HELD`) and the ranges drawn in."""
    import hashlib
    import json

    bounds = ranges(cfg)
    data = {k: v for k, v in cfg.model_dump().items() if k not in UNUSED_SECTIONS}
    for key in (*bounds, *UNUSED_KEYS):
        section, name = key.split(".")
        del data[section][name]
    digest = hashlib.sha256(json.dumps(data, sort_keys=True).encode()).hexdigest()
    kept = {key: getattr(getattr(cfg, key.split(".")[0]), key.split(".")[1]) for key in HELD}
    return {
        "config_sha256": digest,
        "held": kept,
        "ranges": {k: list(v) for k, v in bounds.items()},
    }


def committed(cfg: TwinConfig) -> dict | None:
    """The committed study (:data:`COMMITTED_JSON`) when it was drawn around ``cfg``'s plant, else
    None."""
    import json

    if not COMMITTED_JSON.exists():
        return None
    data = json.loads(COMMITTED_JSON.read_text())
    return data if data.get("plant") == json.loads(json.dumps(plant(cfg))) else None


def committed_write(cfg: TwinConfig, jobs: int = 2) -> dict:
    """Run the study on :data:`COMMITTED_SEEDS` and write :data:`COMMITTED_JSON` (minutes)."""
    from amr_twin.experiments.runner.executor import write_json

    data = {
        "command": "amr-twin experiment chapter5-attainable",
        "samples": COMMITTED_SAMPLES,
        "plant": plant(cfg),
        "seeds": {
            str(seed): summary(study(cfg, COMMITTED_SAMPLES, seed, jobs=jobs))
            for seed in COMMITTED_SEEDS
        },
    }
    write_json(COMMITTED_JSON, data)
    return data


def lines(s: dict) -> list[str]:
    """The summary as text, one line each."""
    n = s["samples"]
    out = [f"{k}: holds in {v} of {n} draws" for k, v in s["held"].items()]
    out += [f"both {k.replace('+', ' and ')}: {v} of {n}" for k, v in s["pairs"].items()]
    out += [
        f"all four: {s['all']} of {n}; best right-minus-left overshoot "
        f"{s['best_right_minus_left_rpm']:.2f} "
        f"RPM (right at most {s['best_right_overshoot_rpm']:.2f}); the PI raised the duty on at "
        f"most "
        f"{s['most_raised_wheels']} of 4 loaded wheels; the 20 kg runs oscillated more in at most "
        f"{s['most_oscillating_more']} of 4 comparisons on both the samples and the true speed; "
        f"the best "
        f"draw's worst unloaded steady error {s['least_worst_steady_error_rpm']:.2f} RPM"
    ]
    return out
