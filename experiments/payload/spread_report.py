"""Outputs of a payload sweep with ``--samples N``: band plots, CSVs, ``summary.json`` and
``summary.md`` (its text from :mod:`.spread_summary`).

``sweep.csv`` (every run, ``sample`` empty for the nominal ones), ``samples.csv`` (each
draw's parameter values), ``intervals.csv`` (per point and metric: nominal, median, 90 %
interval), ``sensitivity.csv`` (rank correlation of each parameter with each answer),
``sweep_<command>.png`` (each metric against payload: nominal line, median and 90 %
band per position), ``sensitivity.png`` (the answers' drivers).
"""

from __future__ import annotations

import csv
import io
import math
from pathlib import Path

from amr_twin.calibration.draw_statistics import LEVEL, noise_level
from amr_twin.experiments.payload import spread
from amr_twin.experiments.payload.rows import PANELS, column_value, rows_csv
from amr_twin.experiments.payload.spread_summary import markdown


def _json_ready(obj):
    if isinstance(obj, float) and not math.isfinite(obj):
        return None if math.isnan(obj) else ("inf" if obj > 0 else "-inf")
    if isinstance(obj, dict):
        return {k: _json_ready(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_json_ready(v) for v in obj]
    return obj


def _table_csv(rows: list[dict]) -> str:
    if not rows:
        return ""
    buffer = io.StringIO()
    writer = csv.DictWriter(buffer, fieldnames=list(rows[0]), lineterminator="\n")
    writer.writeheader()
    writer.writerows(rows)
    return buffer.getvalue()


def plot(results: dict, out_dir: Path) -> list[Path]:
    """One PNG per command (nominal, median and 90 % band per position) and ``sensitivity.png``."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from amr_twin.experiments.runner.executor import save_figure

    nominal, samples = spread.split(results)
    paths = []
    for command in dict.fromkeys(r["command"] for r in nominal):
        fig, axes = plt.subplots(3, 5, figsize=(18, 9), sharex=True)
        for ax, (column, label) in zip(axes.flat, PANELS):
            for n, position in enumerate(dict.fromkeys(r["position"] for r in nominal)):
                colour = f"C{n}"
                mine = [
                    r
                    for r in nominal
                    if r["command"] == command
                    and r["position"] == position
                    and r.get("valid", True)
                ]
                masses = sorted({r["mass_kg"] for r in mine})
                if not masses:
                    continue
                band = [_band(samples, m, position, command, column) for m in masses]
                ax.fill_between(
                    masses,
                    [b[0] for b in band],
                    [b[2] for b in band],
                    color=colour,
                    alpha=0.2,
                    lw=0,
                )
                ax.plot(
                    masses,
                    [b[1] for b in band],
                    "-",
                    color=colour,
                    lw=1.2,
                    label=f"{position} median",
                )
                ax.plot(
                    masses,
                    [
                        column_value(next(r for r in mine if r["mass_kg"] == m), column)
                        for m in masses
                    ],
                    "o--",
                    color=colour,
                    ms=3,
                    lw=0.8,
                    label=f"{position} nominal",
                )
            ax.set_ylabel(label, fontsize=8)
            ax.grid(alpha=0.3)
        for ax in axes[-1]:
            ax.set_xlabel("payload (kg)")
        axes.flat[0].legend(fontsize=6)
        fig.suptitle(
            f"payload sweep, command {command}: nominal (dashed), median and {LEVEL:.0%} band over "
            f"{len(samples)} parameter draws (per-wheel panels: worse driven wheel)"
        )
        fig.tight_layout()
        path = Path(out_dir) / f"sweep_{command.replace(':', '_')}.png"
        save_figure(fig, path)
        paths.append(path)
    paths.append(_plot_sensitivity(results, out_dir, plt))
    return paths


def _band(samples: dict, mass, position, command, column) -> tuple[float, float, float]:
    import numpy as np

    from amr_twin.calibration.draw_statistics import interval

    values = [
        column_value(r, column)
        for rows in samples.values()
        for r in rows
        if (r["mass_kg"], r["position"], r["command"]) == (mass, position, command)
        and r.get("valid", True)
    ]
    i = interval(values)
    return tuple(np.nan if i[k] is None else i[k] for k in ("low", "median", "high"))


def _plot_sensitivity(results: dict, out_dir: Path, plt) -> Path:
    from amr_twin.experiments.runner.executor import save_figure

    sens = results["sensitivity"]
    groups = list(
        dict.fromkeys(
            (r["position"], r["command"], r["answer"]) for r in sens if r["rho"] is not None
        )
    )
    n = max(1, len(groups))
    cols = min(4, n)
    fig, axes = plt.subplots(
        (n + cols - 1) // cols,
        cols,
        figsize=(4.5 * cols, 2.6 * ((n + cols - 1) // cols)),
        squeeze=False,
    )
    limit = noise_level(len(results["draws"]), len(results["draws"].names))
    for ax, (position, command, answer) in zip(axes.flat, groups):
        rows = [
            r
            for r in sens
            if (r["position"], r["command"], r["answer"]) == (position, command, answer)
            and r["rho"] is not None
        ][:6][::-1]
        ax.barh(
            [r["parameter"] for r in rows],
            [r["rho"] for r in rows],
            color=["tab:red" if r["rho"] < 0 else "tab:blue" for r in rows],
        )
        for x in (-limit, limit):
            ax.axvline(x, color="grey", ls=":", lw=0.8)
        ax.set_xlim(-1, 1)
        ax.tick_params(labelsize=6)
        ax.set_title(f"{position} {command} {spread.ANSWER_TEXT[answer]}".strip(), fontsize=7)
    for ax in list(axes.flat)[len(groups) :]:
        ax.axis("off")
    fig.suptitle(
        f"rank correlation with each answer ({len(results['draws'])} draws; dotted: chance level)",
        fontsize=9,
    )
    fig.tight_layout()
    path = Path(out_dir) / "sensitivity.png"
    save_figure(fig, path)
    return path


def analyse(results: dict) -> None:
    """Add ``answers``, ``sensitivity`` and ``intervals`` to ``results`` (before :func:`plot`)."""
    results["answers"] = spread.answers(results)
    results["sensitivity"] = spread.sensitivity(results, results["answers"])
    results["intervals"] = spread.intervals(results)


def report(results: dict, out_dir: Path) -> dict:
    """Write the CSVs, ``summary.json`` and ``summary.md`` (after :func:`analyse`); return the
    summary."""
    from amr_twin.experiments.runner.executor import write_json, write_text
    from amr_twin.experiments.payload.sweep_report import summarise

    out_dir = Path(out_dir)
    draws, found, sens = results["draws"], results["answers"], results["sensitivity"]
    nominal, samples = spread.split(results)
    top = max(r["mass_kg"] for r in nominal)
    write_text(out_dir / "sweep.csv", rows_csv(results["rows"]))
    write_text(out_dir / "samples.csv", _table_csv(draws.table()))
    write_text(out_dir / "intervals.csv", _table_csv(results["intervals"]))
    write_text(out_dir / "sensitivity.csv", _table_csv(sens))
    base = summarise({"rows": nominal})
    summary = {
        "positions": base,
        "answers": _json_ready(found),
        "points": len(nominal),
        "runs": len(results["rows"]),
        "simulated": results["simulated"],
        "reused": results["reused"],
        "wall_s": round(results["wall_s"], 3),
        "duration_s": results["duration_s"],
        "firmware": results["firmware"],
        "samples": {
            "n": len(draws),
            "seed": draws.seed,
            "sampler": draws.sampler,
            "level": LEVEL,
            "parameters": list(draws.names),
            "clipped": draws.clipped,
            "noise_level_rho": round(noise_level(len(draws), len(draws.names)), 4),
        },
    }
    write_json(out_dir / "summary.json", summary)
    write_text(out_dir / "summary.md", markdown(results, base, found, sens, top, len(samples)))
    return summary
