"""The chapter 5 report: one figure per run, and the markdown built from the ``metrics.json`` object."""

from __future__ import annotations

from pathlib import Path

from amr_twin.experiments.chapter5_payload import markdown as payload_markdown
from amr_twin.experiments.chapter5_spread_report import markdown as spread_markdown
from amr_twin.experiments.firmware_comparison import markdown as comparison_markdown

COLUMNS = (("delay_s", "delay s"), ("rise_s", "rise s"), ("peak_s", "peak s"), ("settling_s", "settling s"),
           ("overshoot", "overshoot RPM"), ("steady_error", "steady err RPM"), ("oscillation", "oscillation RPM"))


def _num(value, digits: int = 2) -> str:
    return "—" if value is None else f"{value:.{digits}f}"


def _cell(metrics: dict | None, checks: dict, key: str) -> str:
    value = None if metrics is None else metrics.get(key)
    text = _num(value)
    if key in checks:
        text += " ✓" if checks[key]["verdict"] == "pass" else " ✗"
    return text


def _table(data: dict, source: str, judged: bool) -> list[str]:
    head = "| run | wheel | ref RPM | step | samples | " + " | ".join(h for _, h in COLUMNS) + " |"
    lines = [head, "|" + "---|" * (5 + len(COLUMNS))]
    for r in data["runs"]:
        for wheel, w in r["wheels"].items():
            checks = w["checks"] if judged else {}
            cells = " | ".join(_cell(w[source], checks, k) for k, _ in COLUMNS)
            step = "≤ 75" if w["step_class"] == "small" else "> 75"
            lines.append(f"| {r['run']} | {wheel} | {w['reference_rpm']:.2f} | {step} | {w['samples']} | {cells} |")
    return lines


def _band_table(data: dict) -> list[str]:
    lines = ["| metric | step | wheel | thesis | band |", "|---|---|---|---|---|"]
    for b in data["bands"]:
        step = {"small": "≤ 75 RPM", "large": "> 75 RPM", "any": "any"}[b["step_class"]]
        lines.append(f"| {b['metric']} | {step} | {b['wheel']} | {b['thesis']} | {b['low']} – {b['high']} |")
    return lines


def _misses(data: dict) -> list[str]:
    lines = []
    for r in data["runs"]:
        for wheel, w in r["wheels"].items():
            for metric, c in w["checks"].items():
                if c["verdict"] != "pass":
                    lines.append(f"- run {r['run']} {wheel} wheel: {metric} = {_num(c['twin'])}, "
                                 f"band {c['band'][0]} – {c['band'][1]} (thesis ≈ {c['thesis']})")
        if r["errors"]:
            lines.append(f"- run {r['run']}: command refused: {'; '.join(r['errors'])}")
    for c in data["comparisons"]:
        if c["verdict"] != "pass":
            lines.append(f"- run {c['loaded_run']} (20 kg) {c['wheel']} wheel oscillates "
                         f"{_num(c['loaded'])} RPM, not more than run {c['unloaded_run']} ({_num(c['unloaded'])} RPM)")
    return lines or ["- none"]


def _oscillation(data: dict) -> list[str]:
    """The oscillation section: the measure, its value per run and wheel, the 20 kg comparisons, the verdict."""
    v = data.get("oscillation_verdict")
    if v is None:
        return []
    lines = [f"Named measure: **{v['measure']}**, the {v['definition']}. Judged on the published samples; "
             "the true wheel speed is shown for reference. The analysis is in `docs/validation.md`.", "",
             "| run | payload kg | wheel | ref RPM | published RPM | true RPM |", "|---|---|---|---|---|---|"]
    for r in data["runs"]:
        for wheel, w in r["wheels"].items():
            pub = (w["published"] or {}).get("oscillation")
            lines.append(f"| {r['run']} | {r['payload_kg']:g} | {wheel} | {w['reference_rpm']:.2f} | {_num(pub)} | "
                         f"{_num(w['true'].get('oscillation'))} |")
    lines += ["", "| 20 kg run | unloaded run | wheel | published 20 kg / unloaded | verdict | "
                  "true 20 kg / unloaded | true verdict |", "|---|---|---|---|---|---|---|"]
    for c in data["comparisons"]:
        lines.append(f"| {c['loaded_run']} | {c['unloaded_run']} | {c['wheel']} | {_num(c['loaded'])} / "
                     f"{_num(c['unloaded'])} | {c['verdict']} | {_num(c.get('true_loaded'))} / "
                     f"{_num(c.get('true_unloaded'))} | {c.get('true_verdict', '—')} |")
    if not v["comparisons"]:
        return lines + ["", "**Verdict:** not judged (the runs do not include a 20 kg run and its unloaded twin)."]
    holds = "holds" if v["verdict"] == "pass" else "does not hold"
    lines += ["", f"**Verdict: \"the 20 kg runs oscillate more\" {holds}** — the 20 kg wheel oscillates more in "
                  f"{v['published_passed']} of {v['comparisons']} comparisons on the published samples "
                  f"({v['true_passed']} of {v['comparisons']} on the true speed); the claim needs all of them."]
    return lines


def markdown(data: dict) -> str:
    """The whole ``report.md``."""
    s = data["summary"]
    out = [
        "# Chapter 5 step experiments: twin against thesis", "",
        f"Firmware: **{data['firmware']}**; {len(data['runs'])} runs, {data['sim_s']:.0f} simulated s in "
        f"{data['wall_s']:.1f} s wall time with {data['jobs']} job(s). "
        f"Checks passed: **{s['passed']} / {s['checks']}**.", "",
        f"Judged on the {data['judged_on']}; settling band: {data['settling_band']}. Delay = 50 %, rise = "
        "10 → 90 % of the reference, peak = first maximum, overshoot = peak − reference (0 if below), "
        f"oscillation = {data['oscillation']} after the command (0 for a monotone approach). "
        "✓ inside the band, ✗ outside.", "",
        "## Bands (§5.1.3, §5.1.4)", "", *_band_table(data), "",
        "## Published samples (wheel0_Vel / wheel1_Vel), judged", "", *_table(data, "published", True), "",
        "## True wheel speed (100 Hz), for reference", "", *_table(data, "true", False), "",
        "## The PI's duty with 20 kg (§5.1.4)", "", *payload_markdown(data), "",
        "## Oscillation during the transient: 20 kg against unloaded (§5.1.4)", "", *_oscillation(data), "",
        "## Bands missed", "", *_misses(data), "",
        *(["## Firmware against firmware, sample by sample", "", *comparison_markdown(data["firmware_comparison"]), ""]
          if "firmware_comparison" in data else []),
        *(["## Spread over the parameters' uncertainty", "", *spread_markdown(data["spread"]), ""]
          if "spread" in data else []),
        "## Figures", "",
        *[f"![run {r['run']}: {r['title']}](run{r['run']}.png)\n" for r in data["runs"]],
    ]
    return "\n".join(out) + "\n"


def plot(results: dict, out_dir: Path) -> list[Path]:
    """One PNG per run (``run<N>.png``): RPM against time, each driven wheel and its reference."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np

    from amr_twin.experiments.executor import save_figure

    paths = []
    colours = {"left": "tab:blue", "right": "tab:red"}
    for r in results["runs"]:
        raw = r["raw"]
        fig, ax = plt.subplots(figsize=(7.5, 4.0))
        for w, name in enumerate(("left", "right")):
            info = r["wheels"].get(name)
            if info is None:
                continue
            c, ref = colours[name], abs(info["reference_rpm"])
            t0 = raw["t_command_s"]
            ax.step([0.0, t0, r["duration_s"]], [0.0, ref, ref], where="post", color=c, ls="--", lw=1,
                    label=f"{name} reference {ref:.2f} RPM")
            pub = raw["published"][w]
            ax.plot(np.r_[t0, pub[:, 0]], np.r_[0.0, pub[:, 1]], "o-", color=c, ms=4, lw=1.2,
                    label=f"wheel{w}_Vel (published)")
            ax.plot(raw["t_s"], np.abs(raw["true_rpm"][:, w]), color=c, lw=0.6, alpha=0.6,
                    label=f"{name} true |speed|")
            band = results.get("spread", {}).get("bands", {}).get(r["run"])
            if band is not None:
                ax.fill_between(band["t_s"], band[name]["low"], band[name]["high"], color=c, alpha=0.15, lw=0,
                                label=f"{name} true, 90 % of {len(results['spread']['samples'])} draws")
        ax.set(xlabel="time (s)", ylabel="wheel speed (RPM)", title=f"Run {r['run']}: {r['title']}",
               xlim=(0, r["duration_s"]))
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7, loc="lower right")
        fig.tight_layout()
        path = Path(out_dir) / f"run{r['run']}.png"
        save_figure(fig, path)
        paths.append(path)
    return paths
