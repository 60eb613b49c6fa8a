"""A payload sweep's rows as its reports show them: the columns plotted and summarised
(:data:`PANELS`), a column's value with per-wheel ones at the worse driven wheel
(:func:`column_value`), the rows as CSV (:func:`rows_csv`) and the table of the lowest drive-wheel
loads (:func:`lowest_wheel_loads`)."""

from __future__ import annotations

import csv
import io

import numpy as np

from amr_twin.experiments.chapter5.criteria import WHEELS

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


def column_value(row: dict, column: str) -> float:
    """A row's value of ``column`` (NaN if none); a ``~`` column is per wheel: the worse one's."""
    if not column.startswith("~"):
        v = row.get(column)
        return np.nan if v is None or isinstance(v, str) else float(v)
    values = [row.get(f"{w}_{column[1:]}") for w in WHEELS if row.get(f"{w}_reference_rpm")]
    values = [abs(v) if "error" in column else v for v in values if v is not None]
    return float(max(values)) if values else np.nan


def rows_csv(rows: list[dict]) -> str:
    """The rows as CSV text, every column any row has."""
    columns = list(dict.fromkeys(k for r in rows for k in r))
    buffer = io.StringIO()
    writer = csv.DictWriter(buffer, fieldnames=columns, lineterminator="\n")
    writer.writeheader()
    writer.writerows(rows)
    return buffer.getvalue()


def lowest_wheel_loads(rows: list[dict]) -> list[str]:
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
