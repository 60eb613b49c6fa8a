"""§5.1.4 on the load-true plant: does the PI raise the duty with 20 kg, and what would make it?

The thesis: with 20 kg "the original control action is not sufficient … a PWM signal
with a greater duty cycle has to be used". The twin answers on its own runs:

- :func:`duty_comparison`: per driven wheel of each pair of :data:`PAIRS` (20 kg run,
  unloaded run), the steady ``analogWrite`` counts, motor current and published speed
  over the last quarter of each run; the duty is *raised* when the loaded wheel ends on
  more counts than the unloaded one.
- :func:`rolling_resistance_study`: runs 3 and 7 again with the tyres' and the balls'
  rolling-resistance coefficient both set to each value of :data:`CRR_STUDY`, to find
  the coefficient from which the faithful PI raises the duty. A wheel's speed drop must
  leave the firmware's 4 RPM dead zone (THRESHOLD_CONTROL) before its PI acts at all.
"""

from __future__ import annotations

import numpy as np

PAIRS = ((7, 3), (8, 5))  # (20 kg run, unloaded run)
CRR_STUDY = (0.02, 0.025, 0.03, 0.04)
STUDY_RUNS = (3, 7)
PLAUSIBLE = {"tyres": (0.010, 0.025), "balls": (0.005, 0.03)}  # the sourced ranges in amr.yaml
STEADY_FRACTION = 0.25


def steady(raw: dict, wheel: int) -> dict:
    """Mean counts, motor current and published speed over the last quarter of a run."""
    t = raw["t_s"]
    tail = t >= t[-1] * (1 - STEADY_FRACTION)
    pub = raw["published"][wheel]
    late = pub[pub[:, 0] >= t[-1] * (1 - STEADY_FRACTION), 1] if len(pub) else np.zeros(0)
    return {
        "counts": float(np.mean(raw["pwm_counts"][tail, wheel])),
        "current_a": float(np.mean(raw["current_a"][tail, wheel])),
        "published_rpm": float(late.mean()) if len(late) else None,
        "first_count_change_s": _last_change_s(t, raw["pwm_counts"][:, wheel]),
    }


def _last_change_s(t: np.ndarray, counts: np.ndarray) -> float | None:
    """Time of the last change of the counts (the PI's last action or the ramp's end), s."""
    changes = np.nonzero(np.diff(counts) != 0)[0]
    return float(t[changes[-1] + 1]) if len(changes) else None


def duty_comparison(runs: list[dict]) -> list[dict]:
    """Loaded against unloaded steady duty per driven wheel of each pair (runs with ``raw``)."""
    by_number = {r["run"]: r for r in runs}
    out = []
    for loaded, unloaded in PAIRS:
        if loaded not in by_number or unloaded not in by_number:
            continue
        for w, name in enumerate(("left", "right")):
            if name not in by_number[loaded]["wheels"]:
                continue
            a, b = steady(by_number[loaded]["raw"], w), steady(by_number[unloaded]["raw"], w)
            out.append(
                {
                    "loaded_run": loaded,
                    "unloaded_run": unloaded,
                    "wheel": name,
                    "reference_rpm": by_number[loaded]["wheels"][name]["reference_rpm"],
                    "loaded": a,
                    "unloaded": b,
                    "raised": a["counts"] > b["counts"],
                }
            )
    return out


def study_configs(cfg) -> list:
    """``(crr, cfg)`` for each coefficient of :data:`CRR_STUDY`: tyres and balls both at ``crr``."""
    out = []
    for crr in CRR_STUDY:
        data = cfg.model_dump()
        data["wheel"]["rolling_resistance"] = crr
        data["caster"]["rolling_resistance"] = crr
        out.append((crr, type(cfg).model_validate(data)))
    return out


def rolling_resistance_study(analysed: list[tuple[float, dict]]) -> list[dict]:
    """Duty comparisons per coefficient from the analysed study runs ``(crr, run)``."""
    rows = []
    for crr in CRR_STUDY:
        rows += [{"crr": crr, **c} for c in duty_comparison([r for k, r in analysed if k == crr])]
    return rows


def threshold_crr(shipped: list[dict], study: list[dict], shipped_crr: float) -> float | None:
    """Lowest coefficient at which every wheel of the linear pair (runs 7/3) gets a raised duty."""
    rows = [(shipped_crr, [c for c in shipped if c["loaded_run"] == 7])]
    rows += [
        (crr, [c for c in study if c["crr"] == crr and c["loaded_run"] == 7]) for crr in CRR_STUDY
    ]
    for crr, comps in sorted(rows, key=lambda r: r[0]):
        if comps and all(c["raised"] for c in comps):
            return crr
    return None


def markdown(data: dict) -> list[str]:
    """The report's §5.1.4 duty section, from the ``metrics.json`` object."""
    duty, study = data.get("payload_duty"), data.get("rolling_resistance_study")
    if not duty:
        return ["Not judged (the runs do not include a 20 kg run and its unloaded twin)."]

    def num(v, d=2):
        return "—" if v is None else f"{v:.{d}f}"

    lines = [
        f"Steady values over the last {STEADY_FRACTION:.0%} of each run; rolling resistance as "
        f"shipped "
        f"(tyres {data['crr']['tyres']:g}, balls {data['crr']['balls']:g}).",
        "",
        "| 20 kg run / unloaded | wheel | ref RPM | counts 20 kg / unloaded | current A 20 kg / "
        "unloaded | "
        "published RPM 20 kg / unloaded | duty raised |",
        "|---|---|---|---|---|---|---|",
    ]
    for c in duty:
        a, b = c["loaded"], c["unloaded"]
        lines.append(
            f"| {c['loaded_run']} / {c['unloaded_run']} | {c['wheel']} | "
            f"{c['reference_rpm']:.2f} | "
            f"{num(a['counts'], 1)} / {num(b['counts'], 1)} | {num(a['current_a'])} / "
            f"{num(b['current_a'])} | "
            f"{num(a['published_rpm'])} / {num(b['published_rpm'])} | "
            f"{'yes' if c['raised'] else 'no'} |"
        )
    raised = all(c["raised"] for c in duty)
    lines += [
        "",
        f"**With the shipped plant the faithful firmware "
        f"{'raises' if raised else 'does not raise'} the "
        f"duty with 20 kg** ({sum(c['raised'] for c in duty)} of {len(duty)} wheels).",
    ]
    if study:
        lines += [
            "",
            "Rolling-resistance study (runs 7 / 3, tyres and balls at the same coefficient):",
            "",
            "| Crr | wheel | counts 20 kg / unloaded | published RPM 20 kg / unloaded | raised | "
            "last change of the 20 kg duty s |",
            "|---|---|---|---|---|---|",
        ]
        for c in study:
            a, b = c["loaded"], c["unloaded"]
            lines.append(
                f"| {c['crr']:g} | {c['wheel']} | {num(a['counts'], 1)} / {num(b['counts'], 1)} | "
                f"{num(a['published_rpm'])} / {num(b['published_rpm'])} | "
                f"{'yes' if c['raised'] else 'no'} | "
                f"{num(a['first_count_change_s'])} |"
            )
        t = data.get("threshold_crr")
        lo_t, hi_t = PLAUSIBLE["tyres"]
        lo_b, hi_b = PLAUSIBLE["balls"]
        lines += [
            "",
            (
                f"The faithful PI raises the duty on both wheels of run 7 from **Crr = {t:g}**; "
                f"the sourced "
                f"ranges are {lo_t:g}-{hi_t:g} for the tyres and {lo_b:g}-{hi_b:g} for the "
                f"balls, so this "
                f"is {'within' if t <= hi_t else 'beyond'} what the tyres make plausible."
            )
            if t is not None
            else "No coefficient of the study makes the faithful PI raise the duty on "
            "both wheels of run 7.",
        ]
    return lines
