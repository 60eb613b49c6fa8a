"""The chapter 5 report's section on the spread over parameter draws (from
:func:`.spread.summarise`)."""

from __future__ import annotations


def _num(v, digits: int = 2) -> str:
    return "—" if v is None else f"{v:.{digits}f}"


def markdown(s: dict) -> list[str]:
    """The report's section on the spread."""
    n = s["samples"]
    lines = [
        f"Each run again with {n} parameter draws ({s['sampler']}, seed {s['seed']}, "
        f"{len(s['parameters'])} "
        f"parameters of the body and drive; spreads in `models/amr/README.md`). Median "
        f"({s['level']:.0%} "
        "interval) over the draws beside the thesis; *in band*: draws inside §5.1.3's band; "
        "drivers: the three "
        f"largest rank correlations, **bold** beyond chance (|rho| > {s['noise_level_rho']:.2f}, "
        f"which the largest "
        f"of {len(s['parameters'])} unrelated parameters reaches about one time in 20).",
        "",
        "| run | wheel | metric | thesis | band | twin nominal | twin over the draws | in band "
        "| drivers |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for m in s["metrics"]:
        if "thesis" not in m:
            continue
        drivers = (
            ", ".join(
                ("**`{}` {:+.2f}**" if d.get("notable") else "`{}` {:+.2f}").format(
                    d["parameter"], d["rho"]
                )
                for d in m["drivers"]
            )
            or "—"
        )
        lines.append(
            f"| {m['run']} | {m['wheel']} | {m['metric']} | {m['thesis']} | {m['band'][0]} – "
            f"{m['band'][1]} "
            f"| {_num(m['nominal'])} | {_num(m['median'])} ({_num(m['low'])} – "
            f"{_num(m['high'])}) | "
            f"{m['in_band']} of {n} | {drivers} |"
        )
    checks, card = s["checks_passed"], s["draw_checks"][0] if s["draw_checks"] else None
    if card is not None:
        lines += [
            "",
            f"Checks passed over the draws (each draw's scorecard, as the nominal one's): "
            f"published "
            f"samples median {checks['published']['median']:.0f} "
            f"({checks['published']['low']:.0f} – "
            f"{checks['published']['high']:.0f}) of {card['checks']}, true speed median "
            f"{checks['true']['median']:.0f} ({checks['true']['low']:.0f} – "
            f"{checks['true']['high']:.0f}) of "
            f"{card['true_checks']}; each draw's counts are in `metrics.json` "
            f"(`spread.draw_checks`).",
        ]
    lines += [
        "",
        "True wheel speed (not judged):",
        "",
        "| run | wheel | metric | nominal | over the draws |",
        "|---|---|---|---|---|",
    ]
    for m in s["metrics"]:
        if m["source"] == "true" and m["metric"] in (
            "delay_s",
            "rise_s",
            "settling_s",
            "overshoot",
        ):
            lines.append(
                f"| {m['run']} | {m['wheel']} | {m['metric']} | {_num(m['nominal'])} | "
                f"{_num(m['median'])} "
                f"({_num(m['low'])} – {_num(m['high'])}) |"
            )
    lines += ["", "§5.1.4 over the draws:", ""]
    for d in s["duty_raised"]:
        lines.append(
            f"- run {d['loaded_run']} (20 kg) against run {d['unloaded_run']}, {d['wheel']} "
            f"wheel: the PI "
            f"raises the duty in {d['draws']} of {n} draws"
        )
    for o in s["oscillation_more"]:
        lines.append(
            f"- run {o['loaded_run']} against run {o['unloaded_run']}, {o['wheel']} wheel: the "
            f"20 kg wheel "
            f"oscillates more in {o['draws_published']} of {n} draws (true speed: "
            f"{o['draws_true']})"
        )
    if s["oscillation_more"]:
        lines.append(
            f'- "the 20 kg runs oscillate more" holds on every comparison in '
            f"{s['oscillation_all_hold']} "
            f"of {n} draws"
        )
    halved = s.get("tyre_timestep_halved") or []
    if halved:
        lines += [
            "",
            f"Physics timestep halved by the tyres' guard (stability number S > "
            f"{halved[0]['stability_limit']:g}, "
            "docs/explanation/tyres.md) in "
            + ", ".join(
                f"draw {h['draw']} run {h['run']} ({h['timestep_s'] * 1e3:g} ms)" for h in halved
            )
            + ".",
        ]
    if s["clipped"]:
        lines += [
            "",
            "Draws clipped to a bound: "
            + ", ".join(f"`{k}` {v}" for k, v in s["clipped"].items())
            + ".",
        ]
    return lines
