"""Outputs of the payload sweep: ``sweep.csv``, one PNG per command, ``summary.json`` and ``summary.md``."""

from __future__ import annotations

import csv
import io
from pathlib import Path

import numpy as np

from amr_twin.experiments.chapter5_criteria import WHEELS
from amr_twin.experiments.payload_simulation import TILT_LIMIT_DEG, TIP_MARGIN_MIN_M

PANELS = (  # (column or per-wheel suffix, label); per-wheel ones plot the worse driven wheel
    ("~delay_s", "delay (s)"), ("~settling_s", "settling (s)"), ("~overshoot_rpm", "overshoot (RPM)"),
    ("~steady_error_rpm", "steady error (RPM)"), ("~oscillation_rpm", "oscillation (RPM)"),
    ("~steady_duty", "steady duty (-)"), ("dyn_min_wheel_n", "min wheel load (N)"),
    ("dyn_min_caster_n", "min caster load (N)"), ("max_tilt_deg", "max tilt (deg)"),
    ("static_tip_margin_m", "static tip margin (m)"), ("~max_slip_m_s", "max slip (m/s)"),
    ("~steady_slip_ratio", "steady slip ratio (-)"), ("~steady_current_a", "motor current (A)"),
    ("battery_steady_a", "battery current (A)"), ("energy_j_per_m", "energy per metre (J/m)"),
)
LOWEST_ROWS = 10  # rows of the lowest drive-wheel loads in summary.md


def _value(row: dict, column: str) -> float:
    if not column.startswith("~"):
        v = row.get(column)
        return np.nan if v is None or isinstance(v, str) else float(v)
    values = [row.get(f"{w}_{column[1:]}") for w in WHEELS if row.get(f"{w}_reference_rpm")]
    values = [abs(v) if "error" in column else v for v in values if v is not None]
    return float(max(values)) if values else np.nan


def unsafe_reason(row: dict) -> str:
    """Why a row is not safe ('' when it is)."""
    if row.get("safe"):
        return ""
    if not row.get("valid", True):
        return "invalid position: " + row["error"]
    if row.get("error"):
        return row["error"]
    reasons = []
    if row.get("static_tip_margin_m", -1) < TIP_MARGIN_MIN_M:
        reasons.append(f"tip margin {row.get('static_tip_margin_m')} m < {TIP_MARGIN_MIN_M} m")
    if row.get("wheel_lift_off", True):
        reasons.append(f"drive wheel lift-off (min load {row.get('dyn_min_wheel_n', float('nan')):.1f} N)")
    if row.get("max_tilt_deg", 90) > TILT_LIMIT_DEG:
        reasons.append(f"tilt {row.get('max_tilt_deg', float('nan')):.2f} deg > {TILT_LIMIT_DEG} deg")
    if row.get("motor_overload"):
        worst = max(row.get(f"{w}_steady_current_a") or 0.0 for w in WHEELS)
        reasons.append(f"motor overload: {worst:.1f} A steady, over the driver's continuous rating")
    return "; ".join(reasons)


def summarise(results: dict) -> dict:
    """Highest safe payload per position (all commands), and the invalid points."""
    rows = results["rows"]
    out = {}
    for position in dict.fromkeys(r["position"] for r in rows):
        mine = [r for r in rows if r["position"] == position]
        masses = sorted({r["mass_kg"] for r in mine})
        highest, first_unsafe, reason = None, None, ""
        for m in masses:
            bad = [r for r in mine if r["mass_kg"] == m and not r.get("safe")]
            if bad:
                first_unsafe, reason = m, f"{bad[0]['command']}: {unsafe_reason(bad[0])}"
                break
            highest = m
        tracking = [r["mass_kg"] for r in mine if r.get("tracks")]
        out[position] = {"highest_safe_kg": highest, "first_unsafe_kg": first_unsafe, "reason": reason,
                         "invalid_kg": sorted({r["mass_kg"] for r in mine if not r.get("valid", True)}),
                         "heaviest_tracking_kg": max(tracking) if tracking else None}
    return out


def plot(results: dict, out_dir: Path) -> list[Path]:
    """One PNG per command: each metric against payload mass, one line per position."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from amr_twin.experiments.executor import save_figure

    rows, paths = results["rows"], []
    for command in dict.fromkeys(r["command"] for r in rows):
        fig, axes = plt.subplots(3, 5, figsize=(18, 9), sharex=True)
        for ax, (column, label) in zip(axes.flat, PANELS):
            for position in dict.fromkeys(r["position"] for r in rows):
                pts = sorted((r["mass_kg"], _value(r, column)) for r in rows
                             if r["command"] == command and r["position"] == position and r.get("valid", True))
                if pts:
                    ax.plot(*zip(*pts), "o-", ms=3, lw=1, label=position)
            ax.set_ylabel(label, fontsize=8)
            ax.grid(alpha=0.3)
        for ax in axes[-1]:
            ax.set_xlabel("payload (kg)")
        axes.flat[0].legend(fontsize=6)
        fig.suptitle(f"payload sweep, command {command} (per-wheel panels: worse driven wheel)")
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
    done = sorted((r for r in rows if r.get("dyn_min_wheel_n") is not None), key=lambda r: r["dyn_min_wheel_n"])
    if not done:
        return []
    lines = ["## Lowest drive-wheel loads", "",
             "| mass kg | position | command | wheel | min load N | at s | quasi-static N | mechanism |",
             "|---|---|---|---|---|---|---|---|"]
    for r in done[:LOWEST_ROWS]:
        q = r.get("dyn_min_wheel_quasi_static_n")
        lines.append(f"| {r['mass_kg']:g} | {r['position']} | {r['command']} | {r.get('dyn_min_wheel', '—')} | "
                     f"{r['dyn_min_wheel_n']:.1f} | {r.get('dyn_min_wheel_t_s', float('nan')):.2f} | "
                     f"{'—' if q is None else f'{q:.1f}'} | {r.get('dyn_min_wheel_mechanism', '—')} |")
    return lines


def report(results: dict, out_dir: Path) -> dict:
    """Write ``sweep.csv``, ``summary.json`` and ``summary.md``; return the summary."""
    from amr_twin.experiments.executor import write_json, write_text

    out_dir = Path(out_dir)
    summary = summarise(results)
    write_text(out_dir / "sweep.csv", _csv(results["rows"]))
    write_json(out_dir / "summary.json", {"positions": summary, "points": len(results["rows"]),
                                          "simulated": results["simulated"], "reused": results["reused"],
                                          "wall_s": round(results["wall_s"], 3), "duration_s": results["duration_s"],
                                          "firmware": results["firmware"]})
    lines = ["# Payload sweep", "",
             f"{len(results['rows'])} points ({results['simulated']} simulated, {results['reused']} reused) in "
             f"{results['wall_s']:.1f} s wall time; {results['duration_s']} s per run, firmware {results['firmware']}.",
             "", f"Safe: valid position, simulation ran, static tip margin >= {TIP_MARGIN_MIN_M} m, no drive-wheel "
             f"lift-off, base tilt <= {TILT_LIMIT_DEG} deg, no motor above the driver's continuous current, for every "
             "command and every lighter payload.", "",
             "| position | highest safe kg | first unsafe kg | reason | heaviest tracking kg | invalid at kg |",
             "|---|---|---|---|---|---|"]
    for position, s in summary.items():
        lines.append(f"| {position} | {s['highest_safe_kg']} | {s['first_unsafe_kg'] or '—'} | {s['reason'] or '—'} "
                     f"| {s['heaviest_tracking_kg']} | {', '.join(f'{m:g}' for m in s['invalid_kg']) or '—'} |")
    lines += ["", *_lowest_wheel_loads(results["rows"])]
    lines += ["", *[f"![{p.name}]({p.name})" for p in sorted(out_dir.glob("sweep_*.png"))]]
    write_text(out_dir / "summary.md", "\n".join(lines) + "\n")
    return summary
