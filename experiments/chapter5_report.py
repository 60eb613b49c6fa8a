"""The markdown report of the chapter 5 experiments (built from the ``metrics.json`` object)."""

from __future__ import annotations

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
        "## 20 kg against unloaded: oscillation", "",
        "| loaded run | unloaded run | wheel | loaded RPM | unloaded RPM | verdict |", "|---|---|---|---|---|---|",
        *[f"| {c['loaded_run']} | {c['unloaded_run']} | {c['wheel']} | {_num(c['loaded'])} | "
          f"{_num(c['unloaded'])} | {c['verdict']} |" for c in data["comparisons"]], "",
        "## Bands missed", "", *_misses(data), "",
        "## Figures", "",
        *[f"![run {r['run']}: {r['title']}](run{r['run']}.png)\n" for r in data["runs"]],
    ]
    return "\n".join(out) + "\n"
