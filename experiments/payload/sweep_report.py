"""Outputs of the payload sweep: ``sweep.csv``, one PNG per command, ``summary.json`` and
``summary.md``."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from amr_twin.experiments.payload.limits import (
    CAUSES,
    column_limit,
    limit_causes,
    off_reference,
    unsafe_reason,
)
from amr_twin.experiments.payload.rows import PANELS, column_value, lowest_wheel_loads, rows_csv
from amr_twin.experiments.payload.simulation import TILT_LIMIT_DEG, TIP_MARGIN_MIN_M


def summarise(results: dict) -> dict:
    """Per position: the highest safe payload (the heaviest mass whose every lighter point, all
    commands, is safe), the first unsafe one with its cause, whether the limit lies beyond or
    below the masses swept, and :func:`answer`'s sentence."""
    rows = results["rows"]
    out = {}
    for position in dict.fromkeys(r["position"] for r in rows):
        mine = [r for r in rows if r["position"] == position]
        masses = sorted({r["mass_kg"] for r in mine})
        highest, first_unsafe, reason, causes = None, None, "", []
        for m in masses:
            bad = [r for r in mine if r["mass_kg"] == m and not r.get("safe")]
            if bad:
                first_unsafe, reason = m, f"in {bad[0]['command']}: {unsafe_reason(bad[0])}"
                causes = list(dict.fromkeys(c for r in bad for c, _ in limit_causes(r)))
                break
            highest = m
        tracking = [r["mass_kg"] for r in mine if r.get("tracks")]
        left = [(r["mass_kg"], r["command"], off_reference(r)) for r in mine if off_reference(r)]
        leaves = min(left, key=lambda m: m[0]) if left else None
        entry = {
            "highest_safe_kg": highest,
            "first_unsafe_kg": first_unsafe,
            "reason": reason,
            "causes": causes,
            "lightest_kg": masses[0],
            "heaviest_kg": masses[-1],
            "beyond_grid": first_unsafe is None,
            "below_grid": highest is None,
            "invalid_kg": sorted({r["mass_kg"] for r in mine if not r.get("valid", True)}),
            "heaviest_tracking_kg": max(tracking) if tracking else None,
            "leaves_reference_kg": leaves[0] if leaves else None,
            "leaves_reference": f"in {leaves[1]}: {leaves[2]}" if leaves else "",
        }
        entry["answer"] = answer(entry)
        out[position] = entry
    return out


def answer(s: dict) -> str:
    """One sentence for a position's entry of :func:`summarise`: never "None kg". A wheel that left
    its reference at a mass the criteria call safe is said too."""
    left = s["leaves_reference_kg"]
    early = (
        ""
        if left is None
        else f"from {left:g} kg a wheel leaves its reference {s['leaves_reference']}"
    )
    if s["beyond_grid"]:
        only = s["heaviest_kg"] == s["lightest_kg"]
        text = (
            f"safe at {s['heaviest_kg']:g} kg, the only mass swept: the limit lies beyond it"
            if only
            else f"safe up to {s['heaviest_kg']:g} kg, the heaviest swept: the limit lies beyond "
            f"the masses swept"
        )
        return text + (f" (yet {early})" if early else "")
    if s["below_grid"]:
        lighter = "unloaded" if s["lightest_kg"] == 0 else "no lighter payload was swept"
        return (
            f"no safe payload among the masses swept: unsafe already at {s['first_unsafe_kg']:g} "
            f"kg, the "
            f"lightest ({lighter}), {s['reason']}"
        )
    early = f" (by the criteria; yet {early})" if early and left < s["first_unsafe_kg"] else ""
    return (
        f"highest safe {s['highest_safe_kg']:g} kg{early}; unsafe at {s['first_unsafe_kg']:g} kg "
        f"{s['reason']}"
    )


def _plotted(rows: list[dict]) -> tuple[list[str], dict[str, str]]:
    """The commands with something to plot (a simulated point), and why each other has none."""
    shown, why = [], {}
    for command in dict.fromkeys(r["command"] for r in rows):
        mine = [r for r in rows if r["command"] == command]
        if any(r.get("valid", True) and not r.get("error") for r in mine):
            shown.append(command)
        else:
            why[command] = f"no point of {command} was simulated: {unsafe_reason(mine[0])}"
    return shown, why


def plot(results: dict, out_dir: Path, improved: dict | None = None) -> list[Path]:
    """One PNG per command with a simulated point: each metric against payload mass, one line per
    position (dashed: the improved firmware's points of
    :func:`amr_twin.experiments.payload.sweep.improved_beside`). A command without one gets no PNG
    (:func:`report` says why); a panel without a value says so."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from amr_twin.experiments.runner.executor import save_figure

    rows, paths = results["rows"], []
    lines = [(results["firmware"], rows, "o-")] + (
        [("improved", improved["rows"], "s--")] if improved else []
    )
    for command in _plotted(rows)[0]:
        fig, axes = plt.subplots(3, 5, figsize=(18, 9), sharex=True)
        for ax, (column, label) in zip(axes.flat, PANELS):
            for firmware, some, style in lines:
                for position in dict.fromkeys(r["position"] for r in some):
                    pts = sorted(
                        (r["mass_kg"], v)
                        for r in some
                        if r["command"] == command
                        and r["position"] == position
                        and r.get("valid", True)
                        and not r.get("error")
                        and np.isfinite(v := column_value(r, column))
                    )
                    if pts:
                        name = (
                            position
                            if firmware == results["firmware"]
                            else f"{position}, {firmware}"
                        )
                        ax.plot(*zip(*pts), style, ms=3, lw=1, label=name)
            limit = column_limit(column, rows)
            if ax.lines and limit is not None:
                ax.axhline(limit[0], color="k", ls=":", lw=1, label=f"limit: {limit[1]}")
                ax.text(
                    0.01,
                    limit[0],
                    limit[1],
                    transform=ax.get_yaxis_transform(),
                    fontsize=6,
                    va="bottom",
                )
            if not ax.lines:
                ax.text(
                    0.5,
                    0.5,
                    "no value for any point\n(not defined for this command)",
                    transform=ax.transAxes,
                    ha="center",
                    va="center",
                    fontsize=8,
                    color="0.4",
                )
            ax.set_ylabel(label, fontsize=8)
            ax.grid(alpha=0.3)
        for ax in axes[-1]:
            ax.set_xlabel("payload (kg)")
        handles = next((ax for ax in axes.flat if ax.lines), None)
        if handles is not None:
            axes.flat[0].legend(*handles.get_legend_handles_labels(), fontsize=6)
        fig.suptitle(
            f"payload sweep, command {command}, firmware {results['firmware']} "
            "(per-wheel panels: worse driven wheel)"
        )
        fig.tight_layout()
        path = Path(out_dir) / f"sweep_{command.replace(':', '_')}.png"
        save_figure(fig, path)
        paths.append(path)
    return paths


def report(results: dict, out_dir: Path, improved: dict | None = None) -> dict:
    """Write ``sweep.csv``, ``summary.json`` and ``summary.md``; return the summary (with, per
    position run again with the improved firmware, its own entry under ``"improved"``)."""
    from amr_twin.experiments.runner.executor import write_json, write_text

    out_dir = Path(out_dir)
    summary = summarise(results)
    if improved:
        for position, entry in summarise(improved).items():
            summary[position]["improved"] = entry
    write_text(out_dir / "sweep.csv", rows_csv(results["rows"]))
    write_json(
        out_dir / "summary.json",
        {
            "positions": summary,
            "points": len(results["rows"]),
            "simulated": results["simulated"],
            "reused": results["reused"],
            "wall_s": round(results["wall_s"], 3),
            "duration_s": results["duration_s"],
            "firmware": results["firmware"],
        },
    )
    shown, why = _plotted(results["rows"])
    lines = [
        "# Payload sweep",
        "",
        f"{len(results['rows'])} points ({results['simulated']} simulated, {results['reused']} "
        f"reused) in "
        f"{results['wall_s']:.1f} s wall time; {results['duration_s']} s per run, firmware "
        f"{results['firmware']}"
        + (
            f"; the positions limited by a runaway run again with the improved firmware "
            f"({len(improved['rows'])} points, `improved/runs/`)"
            if improved
            else ""
        )
        + ".",
        "",
        f"Safe: valid position, simulation ran, static tip margin >= {TIP_MARGIN_MIN_M} m, no "
        f"drive-wheel "
        f"lift-off, base tilt <= {TILT_LIMIT_DEG} deg, no motor above the driver's continuous "
        f"current, for every "
        "command and every lighter payload. What limits it, by cause: "
        + "; ".join(f"**{c}**: {CAUSES[c]}" for c in CAUSES)
        + ". A runaway is a limit of the speed "
        "control, not of the motors' rating at what the payload demands: with the payload behind "
        "the axle "
        "the robot oversteers in a turn, and a firmware that does not hold the wheel speeds (the "
        "faithful "
        "one acts once a revolution, not within 4 RPM; the improved one integrates only within 8 "
        "RPM) lets it "
        "pivot; the current drawn then is the runaway's.",
        "",
        "| position | answer | heaviest tracking kg | invalid at kg |",
        "|---|---|---|---|",
    ]
    for position, s in summary.items():
        lines.append(
            f"| {position} | {s['answer']} | {_kg(s['heaviest_tracking_kg'])} | "
            f"{', '.join(f'{m:g}' for m in s['invalid_kg']) or '—'} |"
        )
    beside = [(p, s["improved"]) for p, s in summary.items() if "improved" in s]
    if beside:
        lines += [
            "",
            f"## The same positions with the improved firmware (beside the "
            f"{results['firmware']} one)",
            "",
            f"| position | {results['firmware']} | improved |",
            "|---|---|---|",
        ]
        lines += [f"| {p} | {summary[p]['answer']} | {s['answer']} |" for p, s in beside]
    lines += ["", *lowest_wheel_loads(results["rows"])]
    lines += ["", *[f"- no plot for {c}: {text}" for c, text in why.items()]]
    lines += [
        "",
        *[f"![sweep_{c.replace(':', '_')}.png](sweep_{c.replace(':', '_')}.png)" for c in shown],
    ]
    write_text(out_dir / "summary.md", "\n".join(lines) + "\n")
    return summary


def _kg(value) -> str:
    return "—" if value is None else f"{value:g}"


def answer_lines(summary: dict, results: dict) -> list[str]:
    """What the command line prints: one line per position (and one for its improved firmware's
    run), and one per command left without a plot, with the reason."""
    out = []
    for position, s in summary.items():
        out.append(f"{position:20s} {s['answer']}")
        if "improved" in s:
            out.append(f"{'':20s} improved firmware: {s['improved']['answer']}")
    return out + [f"no plot for {c}: {text}" for c, text in _plotted(results["rows"])[1].items()]
