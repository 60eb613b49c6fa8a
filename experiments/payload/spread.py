"""The payload sweep's answers with their spread over the parameters' uncertainty (``--samples N``).

From the rows of :func:`.sweep.run` with ``draws`` (the nominal rows, then one
row per point and drawn configuration):

- :func:`intervals`: per point and metric, the nominal value, the median and the 90 %
  interval over the draws (``intervals.csv``);
- :func:`answers`: per position, the highest safe payload (as
  :func:`.sweep_report.summarise` decides it) for each draw; per position and
  command, the payload from which a drive wheel lifts off, the base tilts past 3
  degrees, the static tip margin falls below 2 cm and a motor's steady current
  exceeds the driver's continuous rating (the draw's own), each interpolated linearly
  between the swept masses for each draw (``inf``: not within the sweep; the lightest
  mass when it already happens there), with their median and 90 % interval;
- :func:`sensitivity`: the Spearman rank correlation of each drawn parameter with each
  answer, the answers' drivers (``sensitivity.csv``).

:func:`.spread_report.report` writes them with the band plots.
"""

from __future__ import annotations

import math

import numpy as np

from amr_twin.model.statics import CONTACT_MIN_N
from amr_twin.calibration.draw_statistics import interval, noise_level, rank_correlations
from amr_twin.experiments.chapter5.criteria import WHEELS
from amr_twin.experiments.payload.simulation import TILT_LIMIT_DEG, TIP_MARGIN_MIN_M
from amr_twin.experiments.payload.rows import PANELS, column_value
from amr_twin.experiments.payload.sweep_report import summarise

CURRENT_RATIO = (
    "steady_current_ratio"  # the larger motor's steady current over the driver's rating (derived)
)
# answer: (column, limit, direction: +1 when the answer is the mass where it exceeds the limit)
CROSSINGS = (
    ("lift_off_kg", "dyn_min_wheel_n", CONTACT_MIN_N, -1),
    ("tilt_limit_kg", "max_tilt_deg", TILT_LIMIT_DEG, +1),
    ("tip_margin_kg", "static_tip_margin_m", TIP_MARGIN_MIN_M, -1),
    ("overload_kg", CURRENT_RATIO, 1.0, +1),
)
ANSWER_TEXT = {
    "highest_safe_kg": "highest safe payload",
    "lift_off_kg": "a drive wheel lifts off from",
    "tilt_limit_kg": f"tilt above {TILT_LIMIT_DEG:g} deg from",
    "tip_margin_kg": f"static tip margin below {TIP_MARGIN_MIN_M * 100:g} cm from",
    "overload_kg": "a motor over the driver's continuous rating from",
}
TOP = 3  # parameters listed per answer


def split(results: dict) -> tuple[list[dict], dict[int, list[dict]]]:
    """The nominal rows, and the rows of each sample."""
    nominal = [r for r in results["rows"] if r.get("sample") is None]
    samples: dict[int, list[dict]] = {}
    for r in results["rows"]:
        if r.get("sample") is not None:
            samples.setdefault(r["sample"], []).append(r)
    return nominal, samples


def _point(r: dict) -> tuple:
    return r["mass_kg"], r["position"], r["command"]


def intervals(results: dict) -> list[dict]:
    """Per point (mass, position, command) and plotted metric: nominal, median, low, high, n."""
    nominal, samples = split(results)
    by_point: dict[tuple, list[dict]] = {}
    for rows in samples.values():
        for r in rows:
            by_point.setdefault(_point(r), []).append(r)
    out = []
    for r0 in nominal:
        rows = by_point.get(_point(r0), [])
        for column, label in PANELS:
            v0 = column_value(r0, column)
            stats = interval([column_value(r, column) for r in rows if r.get("valid", True)])
            out.append(
                {
                    "mass_kg": r0["mass_kg"],
                    "position": r0["position"],
                    "command": r0["command"],
                    "metric": column.lstrip("~"),
                    "label": label,
                    "nominal": None if not math.isfinite(v0) else v0,
                    **stats,
                    "unsafe_fraction": (sum(not r.get("safe") for r in rows) / len(rows))
                    if rows
                    else None,
                }
            )
    return out


def _column(r: dict, column: str) -> float | None:
    """A row's value; :data:`CURRENT_RATIO` from both motors' steady currents and the row's
    rating."""
    if column != CURRENT_RATIO:
        return r.get(column)
    currents = [r.get(f"{w}_steady_current_a") for w in WHEELS]
    if r.get("current_limit_a") is None or any(i is None for i in currents):
        return None
    return max(currents) / r["current_limit_a"]


def crossing_kg(rows: list[dict], column: str, limit: float, direction: int) -> float:
    """The payload at which ``column`` passes ``limit`` (``direction`` +1: rises above, -1: falls
    below), linear between the swept masses; ``inf`` if it never does, the lightest mass if
    it already has there; NaN when a point did not run."""
    pts = sorted((r["mass_kg"], _column(r, column)) for r in rows if r.get("valid", True))
    if not pts or any(v is None for _, v in pts):
        return math.nan
    past = [direction * (v - limit) > 0 for _, v in pts]
    if past[0]:
        return float(pts[0][0])
    for (m0, v0), (m1, v1), now in zip(pts, pts[1:], past[1:]):
        if now:
            return float(m0 + (m1 - m0) * (limit - v0) / (v1 - v0))
    return math.inf


def answers(results: dict) -> dict:
    """Per position: nominal and per-draw answers with their intervals (see the module notes).

    Returns ``{position: {"highest_safe_kg": {...}, "commands": {command: {answer: {...}}}}}``,
    each answer ``{"nominal", "draws": [per sample], "median", "low", "high", "n", "within"}``
    (``-inf`` in ``draws``: no swept payload is safe; ``within``: the draws in which it happens
    within the swept masses, for the highest safe payload those unsafe below the heaviest).
    """
    nominal, samples = split(results)
    order = sorted(samples)
    out: dict = {}
    base = summarise({"rows": nominal})
    per_sample = {s: summarise({"rows": samples[s]}) for s in order}
    for position in base:

        def safe(summary: dict) -> float:
            v = summary[position]["highest_safe_kg"]
            return -math.inf if v is None else float(v)

        draws = [safe(per_sample[s]) for s in order]
        top = max(r["mass_kg"] for r in nominal)
        entry = {
            "highest_safe_kg": {
                "nominal": safe(base),
                "draws": draws,
                **interval(draws, discrete=True),
                "within": sum(v < top for v in draws),
            },
            "commands": {},
        }
        for command in dict.fromkeys(r["command"] for r in nominal):

            def mine(rows: list[dict]) -> list[dict]:
                return [r for r in rows if r["position"] == position and r["command"] == command]

            entry["commands"][command] = {}
            for name, column, limit, direction in CROSSINGS:
                values = [crossing_kg(mine(samples[s]), column, limit, direction) for s in order]
                entry["commands"][command][name] = {
                    "nominal": crossing_kg(mine(nominal), column, limit, direction),
                    "draws": values,
                    **interval(values, discrete=True),
                    "within": sum(math.isfinite(v) for v in values),
                }
        out[position] = entry
    return out


def sensitivity(results: dict, found: dict) -> list[dict]:
    """Rank correlation of every drawn parameter with every answer of :func:`answers`.

    Returns one row per answer and parameter: ``position, command ('' for the highest safe
    payload), answer, parameter, rho, notable`` (|rho| above
    :func:`~amr_twin.calibration.draw_statistics.noise_level` for all the drawn parameters),
    sorted by answer, then |rho| descending.
    """
    draws = results["draws"]
    _, samples = split(results)
    x = draws.values[sorted(samples)]
    limit = noise_level(len(x), len(draws.names))
    rows = []

    def add(position: str, command: str, answer: str, values: list[float]) -> None:
        rho = rank_correlations(x, values)
        ranked = sorted(range(len(rho)), key=lambda j: -abs(rho[j]) if np.isfinite(rho[j]) else 0.0)
        for j in ranked:
            rows.append(
                {
                    "position": position,
                    "command": command,
                    "answer": answer,
                    "parameter": draws.names[j],
                    "rho": None if not np.isfinite(rho[j]) else round(float(rho[j]), 4),
                    "notable": bool(np.isfinite(rho[j]) and abs(rho[j]) > limit),
                }
            )

    for position, entry in found.items():
        add(position, "", "highest_safe_kg", entry["highest_safe_kg"]["draws"])
        for command, per in entry["commands"].items():
            for name, *_ in CROSSINGS:
                add(position, command, name, per[name]["draws"])
    return rows


def drivers(
    sens: list[dict], position: str, command: str, answer: str, top: int = TOP
) -> list[dict]:
    """The ``top`` parameters of one answer by |rho| (``notable`` marks those beyond chance)."""
    return [
        r
        for r in sens
        if (r["position"], r["command"], r["answer"]) == (position, command, answer)
        and r["rho"] is not None
    ][:top]
