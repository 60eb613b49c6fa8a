"""Outputs of the payload sweep: ``sweep.csv``, one PNG per command, ``summary.json`` and
``summary.md``."""

from __future__ import annotations

import csv
import io
from pathlib import Path

import numpy as np

from amr_twin.experiments.chapter5.criteria import WHEELS
from amr_twin.experiments.payload.simulation import (
    RUNAWAY_RPM,
    TILT_LIMIT_DEG,
    TIP_MARGIN_MIN_M,
    TRACK_TOLERANCE_RPM,
)

PANELS = (  # (column or per-wheel suffix, label); per-wheel ones plot the worse driven wheel
    ("~delay_s", "delay (s)"),
    ("~settling_s", "settling (s)"),
    ("~overshoot_rpm", "overshoot (RPM)"),
    ("~steady_error_rpm", "steady error (RPM)"),
    ("~oscillation_rpm", "oscillation (RPM)"),
    ("~steady_duty", "steady duty (-)"),
    ("dyn_min_wheel_n", "min wheel load (N)"),
    ("dyn_min_caster_n", "min caster load (N)"),
    ("max_tilt_deg", "max tilt (deg)"),
    ("static_tip_margin_m", "static tip margin (m)"),
    ("~max_slip_m_s", "max slip (m/s)"),
    ("~steady_slip_ratio", "steady slip ratio (-)"),
    ("~steady_current_a", "motor current (A)"),
    ("battery_steady_a", "battery current (A)"),
    ("energy_j_per_m", "energy per metre (J/m)"),
)
LOWEST_ROWS = 10  # rows of the lowest drive-wheel loads in summary.md


def _value(row: dict, column: str) -> float:
    if not column.startswith("~"):
        v = row.get(column)
        return np.nan if v is None or isinstance(v, str) else float(v)
    values = [row.get(f"{w}_{column[1:]}") for w in WHEELS if row.get(f"{w}_reference_rpm")]
    values = [abs(v) if "error" in column else v for v in values if v is not None]
    return float(max(values)) if values else np.nan


CAUSES = {
    "invalid": "invalid payload",
    "refused": "command refused",
    "failed": "simulation failed",
    "runaway": "runaway (the wheels leave their references; the motor current follows)",
    "overload": "motor current rating (wheels tracking)",
    "tipping": "tipping (static tip margin)",
    "lift-off": "drive-wheel lift-off",
    "tilt": "base tilt",
}
"""What limits a payload, by the criteria a point fails (``limit_causes``). A motor over its
rating while a wheel does not hold its reference (its true speed over the run's last quarter
more than the PI's 4 RPM dead zone off) is a **runaway**: a limit of the speed control (a robot
heavy at the rear oversteers in the turn and, its wheels not held, pivots), not the current the
payload demands in a tracked turn."""


def limit_causes(row: dict) -> list[tuple[str, str]]:
    """``[(cause, detail)]``: why a row is not safe (empty when it is); causes of :data:`CAUSES`."""
    if row.get("safe"):
        return []
    if not row.get("valid", True):
        return [("invalid", row["error"])]
    if row.get("error"):
        return [
            ("refused" if row["error"].startswith("command refused") else "failed", row["error"])
        ]
    out = []
    if row.get("motor_overload"):
        worst = max(row.get(f"{w}_steady_current_a") or 0.0 for w in WHEELS)
        rating = row.get("current_limit_a")
        current = f"{worst:.1f} A steady" + (f" > {rating:.1f} A" if rating is not None else "")
        off = _farthest(row)
        if off is None:
            out.append(("overload", current))
        else:
            out.append(("runaway", f"{off}, {current}"))
    if row.get("static_tip_margin_m", -1) < TIP_MARGIN_MIN_M:
        out.append(("tipping", f"{row.get('static_tip_margin_m')} m < {TIP_MARGIN_MIN_M} m"))
    if row.get("wheel_lift_off", True):
        out.append(("lift-off", f"min load {row.get('dyn_min_wheel_n', float('nan')):.1f} N"))
    if row.get("max_tilt_deg", 90) > TILT_LIMIT_DEG:
        out.append(
            ("tilt", f"{row.get('max_tilt_deg', float('nan')):.2f} deg > {TILT_LIMIT_DEG} deg")
        )
    return out


def _farthest(row: dict) -> str | None:
    """The driven wheel whose true speed (the run's last quarter) left its reference by more than
    :data:`~amr_twin.experiments.payload.simulation.RUNAWAY_RPM`, in words; None if none did."""
    off = max(
        (
            (abs(e), w)
            for w in WHEELS
            if row.get(f"{w}_reference_rpm")
            and (e := row.get(f"{w}_true_steady_error_rpm")) is not None
        ),
        default=(0.0, ""),
    )
    if off[0] <= RUNAWAY_RPM:
        return None
    ref = abs(row[f"{off[1]}_reference_rpm"])
    speed = (
        ref + row[f"{off[1]}_true_steady_error_rpm"]
    )  # along the reference: < 0 turning backward
    return f"{off[1]} wheel at {speed:.0f} RPM against {ref:.1f}"


def unsafe_reason(row: dict) -> str:
    """Why a row is not safe ('' when it is), in words."""
    return "; ".join(f"{CAUSES[c]}: {d}" for c, d in limit_causes(row))


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
        left = [(r["mass_kg"], r["command"], _farthest(r)) for r in mine if _farthest(r)]
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


def _limit(column: str, rows: list[dict]) -> tuple[float, str] | None:
    """The line a panel's values are judged against (a point's safety or tracking), if any."""
    from amr_twin.model.statics import CONTACT_MIN_N

    rating = next(
        (r["current_limit_a"] for r in rows if r.get("current_limit_a") is not None), None
    )
    limits = {
        "~steady_current_a": (rating, "driver's continuous rating"),
        "max_tilt_deg": (TILT_LIMIT_DEG, "tilt"),
        "static_tip_margin_m": (TIP_MARGIN_MIN_M, "tip margin"),
        "dyn_min_wheel_n": (CONTACT_MIN_N, "lift-off"),
        "~steady_error_rpm": (TRACK_TOLERANCE_RPM, "tracking (the PI's dead zone)"),
    }
    value, name = limits.get(column, (None, ""))
    return None if value is None else (float(value), name)


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
                        and np.isfinite(v := _value(r, column))
                    )
                    if pts:
                        name = (
                            position
                            if firmware == results["firmware"]
                            else f"{position}, {firmware}"
                        )
                        ax.plot(*zip(*pts), style, ms=3, lw=1, label=name)
            limit = _limit(column, rows)
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


def _csv(rows: list[dict]) -> str:
    columns = list(dict.fromkeys(k for r in rows for k in r))
    buffer = io.StringIO()
    writer = csv.DictWriter(buffer, fieldnames=columns, lineterminator="\n")
    writer.writeheader()
    writer.writerows(rows)
    return buffer.getvalue()


def _lowest_wheel_loads(rows: list[dict]) -> list[str]:
    """The points whose drive wheel came closest to lifting, with the mechanism and the
    quasi-static load of the accelerations at that instant (a hand check of the dynamics)."""
    done = sorted(
        (r for r in rows if r.get("dyn_min_wheel_n") is not None),
        key=lambda r: r["dyn_min_wheel_n"],
    )
    if not done:
        return []
    lines = [
        "## Lowest drive-wheel loads",
        "",
        "| mass kg | position | command | wheel | min load N | at s | quasi-static N | mechanism |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for r in done[:LOWEST_ROWS]:
        q = r.get("dyn_min_wheel_quasi_static_n")
        lines.append(
            f"| {r['mass_kg']:g} | {r['position']} | {r['command']} | "
            f"{r.get('dyn_min_wheel', '—')} | "
            f"{r['dyn_min_wheel_n']:.1f} | {r.get('dyn_min_wheel_t_s', float('nan')):.2f} | "
            f"{'—' if q is None else f'{q:.1f}'} | {r.get('dyn_min_wheel_mechanism', '—')} |"
        )
    return lines


def report(results: dict, out_dir: Path, improved: dict | None = None) -> dict:
    """Write ``sweep.csv``, ``summary.json`` and ``summary.md``; return the summary (with, per
    position run again with the improved firmware, its own entry under ``"improved"``)."""
    from amr_twin.experiments.runner.executor import write_json, write_text

    out_dir = Path(out_dir)
    summary = summarise(results)
    if improved:
        for position, entry in summarise(improved).items():
            summary[position]["improved"] = entry
    write_text(out_dir / "sweep.csv", _csv(results["rows"]))
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
    lines += ["", *_lowest_wheel_loads(results["rows"])]
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
