"""The chapter 5 report: one figure per run, and the markdown built from the ``metrics.json``
object."""

from __future__ import annotations

from amr_twin.experiments.chapter5.findings import ATTAINABLE_SECTION
from amr_twin.experiments.chapter5.findings_section import attainable, bound_table, opening
from amr_twin.experiments.chapter5.payload import markdown as payload_markdown
from amr_twin.experiments.chapter5.readings import markdown as readings_markdown
from amr_twin.experiments.chapter5.spread_report import markdown as spread_markdown
from amr_twin.experiments.chapter5.firmware_comparison import markdown as comparison_markdown

COLUMNS = (
    ("delay_s", "delay s"),
    ("rise_s", "rise s"),
    ("peak_s", "peak s"),
    ("settling_s", "settling s"),
    ("overshoot", "overshoot RPM"),
    ("steady_error", "steady err RPM"),
    ("oscillation", "oscillation RPM"),
)


def _num(value, digits: int = 2) -> str:
    return "—" if value is None else f"{value:.{digits}f}"


def _cell(metrics: dict | None, checks: dict, key: str) -> str:
    value = None if metrics is None else metrics.get(key)
    text = _num(value)
    if key in checks:
        text += " ✓" if checks[key]["verdict"] == "pass" else " ✗"
    return text


def _table(data: dict, source: str, checks_key: str) -> list[str]:
    """One row per run and wheel; the published table lists the samples each metric rests on."""
    published = source == "published"
    head = (
        "| run | wheel | ref RPM | step | "
        + ("samples | " if published else "")
        + " | ".join(h for _, h in COLUMNS)
        + " |"
    )
    lines = [head, "|" + "---|" * ((5 if published else 4) + len(COLUMNS))]
    for r in data["runs"]:
        for wheel, w in r["wheels"].items():
            cells = " | ".join(_cell(w[source], w[checks_key], k) for k, _ in COLUMNS)
            step = "≤ 75" if w["step_class"] == "small" else "> 75"
            samples = f"{w['samples']} | " if published else ""
            lines.append(
                f"| {r['run']} | {wheel} | {w['reference_rpm']:.2f} | {step} | {samples}{cells} |"
            )
    return lines


def _band_table(data: dict) -> list[str]:
    lines = ["| metric | step | wheel | thesis | band | source |", "|---|---|---|---|---|---|"]
    for b in data["bands"]:
        step = {"small": "≤ 75 RPM", "large": "> 75 RPM", "any": "any"}[b["step_class"]]
        lines.append(
            f"| {b['metric']} | {step} | {b['wheel']} | {b['thesis']} | {b['low']} – {b['high']} | "
            f"{b.get('source', '')} |"
        )
    return lines


def passed_by_metric(data: dict, checks_key: str) -> str:
    """``delay_s 0 / 14, ...``: how many of each metric's checks pass."""
    counts: dict[str, list[int]] = {}
    for r in data["runs"]:
        for w in r["wheels"].values():
            for metric, c in w[checks_key].items():
                n = counts.setdefault(metric, [0, 0])
                n[0] += c["verdict"] == "pass"
                n[1] += 1
    return ", ".join(f"{m} {p} / {n}" for m, (p, n) in counts.items())


def _misses(data: dict) -> list[str]:
    lines = []
    for r in data["runs"]:
        for wheel, w in r["wheels"].items():
            for metric, c in w["checks"].items():
                if c["verdict"] != "pass":
                    lines.append(
                        f"- run {r['run']} {wheel} wheel: {metric} = {_num(c['twin'])}, "
                        f"band {c['band'][0]} – {c['band'][1]} (thesis ≈ {c['thesis']})"
                    )
        if r["errors"]:
            lines.append(f"- run {r['run']}: command refused: {'; '.join(r['errors'])}")
    for c in data["comparisons"]:
        if c["verdict"] != "pass":
            lines.append(
                f"- run {c['loaded_run']} (20 kg) {c['wheel']} wheel oscillates "
                f"{_num(c['loaded'])} RPM, not more than run {c['unloaded_run']} "
                f"({_num(c['unloaded'])} RPM)"
            )
    return lines or ["- none"]


def _oscillation(data: dict) -> list[str]:
    """The oscillation section: the measure, its value per run and wheel, the 20 kg comparisons, the
    verdict."""
    v = data.get("oscillation_verdict")
    if v is None:
        return []
    lines = [
        f"Named measure: **{v['measure']}**, the {v['definition']}. Judged on the published "
        f"samples; "
        "the true wheel speed is shown for reference. The analysis is in "
        "`docs/explanation/validation.md`.",
        "",
        "| run | payload kg | wheel | ref RPM | published RPM | true RPM |",
        "|---|---|---|---|---|---|",
    ]
    for r in data["runs"]:
        for wheel, w in r["wheels"].items():
            pub = (w["published"] or {}).get("oscillation")
            lines.append(
                f"| {r['run']} | {r['payload_kg']:g} | {wheel} | {w['reference_rpm']:.2f} | "
                f"{_num(pub)} | "
                f"{_num(w['true'].get('oscillation'))} |"
            )
    lines += [
        "",
        "| 20 kg run | unloaded run | wheel | published 20 kg / unloaded | verdict | "
        "true 20 kg / unloaded | true verdict |",
        "|---|---|---|---|---|---|---|",
    ]
    for c in data["comparisons"]:
        lines.append(
            f"| {c['loaded_run']} | {c['unloaded_run']} | {c['wheel']} | {_num(c['loaded'])} / "
            f"{_num(c['unloaded'])} | {c['verdict']} | {_num(c.get('true_loaded'))} / "
            f"{_num(c.get('true_unloaded'))} | {c.get('true_verdict', '—')} |"
        )
    if not v["comparisons"]:
        return lines + [
            "",
            "**Verdict:** not judged (the runs do not include a 20 kg run and its unloaded twin).",
        ]
    holds = "holds" if v["verdict"] == "pass" else "does not hold"
    lines += [
        "",
        f'**Verdict: "the 20 kg runs oscillate more" {holds}** — the 20 kg wheel oscillates more '
        f"in "
        f"{v['published_passed']} of {v['comparisons']} comparisons on the published samples "
        f"({v['true_passed']} of {v['comparisons']} on the true speed); the claim needs all of "
        f"them.",
    ]
    return lines


def markdown(data: dict) -> str:
    """The whole ``report.md``."""
    s = data["summary"]
    study = data.get("study_runs", 0)
    runs = f"{len(data['runs'])} runs ({data['sim_s']:.0f} simulated s)" + (
        f" and {study} rolling-resistance study runs ({data['study_sim_s']:.0f} s), "
        f"{len(data['runs']) + study} runs and {data['sim_s'] + data['study_sim_s']:.0f} "
        f"simulated s in all,"
        if study
        else ""
    )
    out = [
        "# Chapter 5 step experiments: twin against thesis",
        "",
        *opening(data),
        f"## {ATTAINABLE_SECTION}",
        "",
        *attainable(data),
        "",
        f"Firmware: **{data['firmware']}**; {runs} in {data['wall_s']:.1f} s wall time with "
        f"{data['jobs']} job(s). "
        f"All checks on the published samples, attainable or not: {s['passed']} / {s['checks']}; "
        f"the true "
        f"wheel speed against the same bands: {s['true_passed']} / {s['true_checks']}.",
        "",
        f"Judged on the {data['judged_on']}; settling band: {data['settling_band']}. Definitions: "
        f"{data['definitions']}; oscillation = {data['oscillation']} after the command (0 for a "
        f"monotone "
        "approach). Signed values (reference, final value, steady error) carry the reference's "
        "sign: a wheel "
        "commanded backward has a negative reference. ✓ inside the band, ✗ outside.",
        "",
        "## Bands (§5.1.3, §5.1.4)",
        "",
        *_band_table(data),
        "",
        "## Published samples (wheel0_Vel / wheel1_Vel), judged",
        "",
        f"Passed by metric: {passed_by_metric(data, 'checks')}.",
        "",
        *_table(data, "published", "checks"),
        "",
        *bound_table(data),
        *(
            [
                "## How the thesis may have timed its plots: readings of the same samples",
                "",
                *readings_markdown(data["readings"]),
                "",
            ]
            if "readings" in data
            else []
        ),
        "## True wheel speed (100 Hz), against the same bands",
        "",
        f"Not visible on the thesis' topics; shown because its timings are not limited by one "
        f"sample per "
        f"revolution. Passed by metric: {passed_by_metric(data, 'true_checks')}.",
        "",
        *_table(data, "true", "true_checks"),
        "",
        "## The PI's duty with 20 kg (§5.1.4)",
        "",
        *payload_markdown(data),
        "",
        "## Oscillation during the transient: 20 kg against unloaded (§5.1.4)",
        "",
        *_oscillation(data),
        "",
        "## Bands missed",
        "",
        *_misses(data),
        "",
        *(
            [
                "## Firmware against firmware, sample by sample",
                "",
                *comparison_markdown(data["firmware_comparison"]),
                "",
            ]
            if "firmware_comparison" in data
            else []
        ),
        *(
            ["## Spread over the parameters' uncertainty", "", *spread_markdown(data["spread"]), ""]
            if "spread" in data
            else []
        ),
        "## Figures",
        "",
        *[f"![run {r['run']}: {r['title']}](run{r['run']}.png)\n" for r in data["runs"]],
    ]
    return "\n".join(out) + "\n"
