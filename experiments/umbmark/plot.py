"""The figures of ``amr-twin experiment umbmark``: the Borenstein plot ``borenstein.png`` (each
run's return error, both clusters and their centres of gravity, before and after the calibration, a
panel per seed) and ``emax.png`` (E_max,syst per seed before and after), from the data of
:func:`.report.write`."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from amr_twin.experiments.runner.executor import save_figure

MAX_PANELS = 12
"""Seeds drawn in the Borenstein plot (the first ones; every seed is in the tables)."""


def plot_borenstein(data: dict, path: Path) -> None:
    """A panel per seed: every run's return error (mm), CW and CCW, before (hollow) and after
    (filled), and the four centres of gravity (crosses, joined to the origin)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    seeds = data["per_seed"][:MAX_PANELS]
    cols = min(len(seeds), 4)
    rows = math.ceil(len(seeds) / cols)
    fig, axes = plt.subplots(
        rows,
        cols,
        figsize=(3.6 * cols + 0.5, 3.6 * rows + 0.6),
        squeeze=False,
        layout="constrained",
    )
    colours = {"cw": "tab:blue", "ccw": "tab:red"}
    for ax, d in zip(axes.ravel(), seeds):
        for phase, filled in (("before", False), ("after", True)):
            p = d[phase]
            if p is None:
                continue
            for direction, c in colours.items():
                e = np.array([r["error_m"] for r in p["runs"] if r["direction"] == direction]) * 1e3
                ax.plot(
                    e[:, 0],
                    e[:, 1],
                    "o",
                    ms=4,
                    color=c,
                    mfc=c if filled else "none",
                    label=f"{direction.upper()} {phase}",
                )
                cg = p["node"][direction]
                ax.plot(
                    [0, 1e3 * cg["x_cg_m"]],
                    [0, 1e3 * cg["y_cg_m"]],
                    "-",
                    color=c,
                    lw=0.8,
                    alpha=1.0 if filled else 0.5,
                )
                ax.plot(1e3 * cg["x_cg_m"], 1e3 * cg["y_cg_m"], "x", color=c, ms=9, mew=2)
        ax.axhline(0, color="0.7", lw=0.5)
        ax.axvline(0, color="0.7", lw=0.5)
        ax.set_aspect("equal", adjustable="datalim")
        after = f", after {1e3 * d['after']['node']['e_max_syst_m']:.0f}" if d["after"] else ""
        ax.set_title(
            f"seed {d['seed']}: E_max,syst "
            f"{1e3 * d['before']['node']['e_max_syst_m']:.0f}{after} mm",
            fontsize=9,
        )
        ax.grid(alpha=0.3)
    for ax in axes.ravel()[len(seeds) :]:
        ax.set_visible(False)
    axes[0, 0].legend(fontsize=7, loc="best")
    for ax in axes[:, 0]:
        ax.set_ylabel("y error, mm")
    for ax in axes[-1, :]:
        ax.set_xlabel("x error, mm")
    shown = (
        ""
        if len(data["per_seed"]) <= MAX_PANELS
        else f" (first {MAX_PANELS} of {len(data['per_seed'])} seeds)"
    )
    fig.suptitle(
        "UMBmark return errors (true - odometry)\nruns (o), centres of gravity (x); hollow before, "
        f"filled after the calibration{shown}",
        fontsize=9,
    )
    save_figure(fig, path)


def plot_emax(data: dict, path: Path) -> None:
    """E_max,syst per seed before and after (log scale), and each seed's scatter as the floor of
    what a calibration can reach."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    per = data["per_seed"]
    x = np.arange(len(per))
    fig, ax = plt.subplots(figsize=(max(6.0, 0.55 * len(per) + 2), 4), layout="constrained")
    before = [1e3 * d["before"]["node"]["e_max_syst_m"] for d in per]
    ax.plot(x, before, "o", color="tab:red", label="E_max,syst before")
    if per[0]["after"] is not None:
        ax.plot(
            x,
            [1e3 * d["after"]["node"]["e_max_syst_m"] for d in per],
            "o",
            color="tab:green",
            label="E_max,syst after the calibration",
        )
    ax.plot(
        x,
        [1e3 * d["before"]["node"]["e_nonsyst_rms_m"] for d in per],
        "_",
        color="k",
        ms=14,
        label="scatter of the return errors (RMS), before",
    )
    ax.set_yscale("log")
    ax.set_xticks(x, [str(d["seed"]) for d in per])
    ax.set_xlabel("seed (robot)")
    ax.set_ylabel("mm")
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=8)
    ax.set_title("UMBmark per robot: one dot per seed")
    save_figure(fig, path)
