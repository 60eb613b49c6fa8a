"""The chapter 5 figures: one PNG per run, one panel per driven wheel, with the thesis' bands.

Each panel shows, in |RPM| against time from the start of the record:

* the published samples (``wheel0_Vel``/``wheel1_Vel``) as markers, each held by a thin step
  until the next (what a subscriber holds), from the first sample on: nothing is drawn
  before it, since the firmware publishes nothing until the wheel has turned once;
* the true wheel speed (100 Hz) as a thin line, and the reference as a dashed line;
* the bands the report scores the published samples against (§5.1.3, fig. 5.3;
  :data:`amr_twin.experiments.chapter5.criteria.BANDS`), drawn where they apply: the delay
  band on the 50 % level of the final value, the rise band on the 90 % level counted from
  the published 10 % crossing, the thesis' peak as a box (peak time x overshoot above the
  final value), the settling band around the final value from the latest settling time
  allowed, and the steady-error band (the reference +- 4 RPM) over the record's last 20 %,
  each in its own colour and hatch (:data:`BAND_STYLE`) and named in the legend;
* under listing 4.12 (one speed per revolution: every firmware but the improved one), the
  time before the earliest first published sample, one revolution at the reference
  (60/|rpm| s) after the command, hatched grey and annotated: no band left of it can be met
  on the published samples (:mod:`amr_twin.experiments.chapter5.findings`).
"""

from __future__ import annotations

from pathlib import Path

from amr_twin.analysis.metrics import first_crossing_s
from amr_twin.experiments.chapter5.criteria import BANDS, step_class

COLOURS = {"left": "tab:blue", "right": "tab:red"}
BAND_STYLE = {
    "delay_s": ("tab:purple", None),
    "rise_s": ("tab:orange", None),
    "peak_s": ("tab:green", "//"),
    "settling_s": ("tab:cyan", ".."),
    "steady_error": ("tab:brown", None),
    "first_sample": ("0.5", "xx"),
}
"""Colour and hatch of each thesis band, and of the time before the earliest first published
sample."""
CAPTION = (
    "Grey hatching: listing 4.12 publishes one speed per wheel revolution, so no published sample "
    "comes before one revolution at the reference after the command (T = 60/|rpm| s). Whatever the "
    "plant, the published peak comes no earlier than T, the delay (50 %) no earlier than T/2, "
    "and the "
    "rise (10-90 %) takes at least 0.8 T (report.md; docs/explanation/validation.md)."
)


def _bands(wheel: str, reference_rpm: float) -> dict:
    """The bands of ``wheel`` at this step, by metric: ``(low, high, thesis)``."""
    cls = step_class(reference_rpm)
    return {
        b.metric: (b.low, b.high, b.thesis)
        for b in BANDS
        if b.step_class in ("any", cls) and b.wheel in ("any", wheel)
    }


def _panel(ax, run: dict, results: dict, w: int, name: str) -> None:
    import numpy as np

    raw, info = run["raw"], run["wheels"][name]
    colour, ref, t0 = COLOURS[name], abs(info["reference_rpm"]), raw["t_command_s"]
    end = run["duration_s"]
    direction = " (backward)" if info["reference_rpm"] < 0 else ""
    ax.step(
        [0.0, t0, end],
        [0.0, ref, ref],
        where="post",
        color="k",
        ls="--",
        lw=1,
        label=f"reference {ref:.2f} RPM{direction}",
    )
    pub = raw["published"][w]
    if len(pub):
        ax.step(
            np.r_[pub[:, 0], end],
            np.r_[pub[:, 1], pub[-1, 1]],
            where="post",
            color=colour,
            lw=0.6,
            alpha=0.5,
        )
        ax.plot(
            pub[:, 0],
            pub[:, 1],
            "o",
            color=colour,
            ms=4,
            label=f"wheel{w}_Vel, {len(pub)} published samples (held until the next)",
        )
    ax.plot(
        raw["t_s"],
        np.abs(raw["true_rpm"][:, w]),
        color=colour,
        lw=0.7,
        alpha=0.6,
        label="true |speed|, 100 Hz",
    )
    spread = results.get("spread", {}).get("bands", {}).get(run["run"])
    if spread is not None:
        ax.fill_between(
            spread["t_s"],
            spread[name]["low"],
            spread[name]["high"],
            color=colour,
            alpha=0.15,
            lw=0,
            label=f"true, 90 % of {len(results['spread']['samples'])} draws",
        )
    metrics = info["published"]
    if metrics is None:
        ax.text(0.5, 0.5, "no published sample", transform=ax.transAxes, ha="center")
        return
    final = abs(metrics["final_value"])
    bands = _bands(name, info["reference_rpm"])
    if results.get("firmware") != "improved":
        _first_sample(ax, t0, ref)
    colour, _ = BAND_STYLE["delay_s"]
    lo, hi, _ = bands["delay_s"]
    ax.plot(
        [t0 + lo, t0 + hi],
        [0.5 * final] * 2,
        color=colour,
        lw=5,
        alpha=0.8,
        solid_capstyle="butt",
        label=f"thesis bands (§5.1.3, fig. 5.3): delay {lo:g}-{hi:g} s at 50 %",
    )
    t10 = first_crossing_s(
        np.r_[t0, pub[:, 0]], np.r_[0.0, pub[:, 1]], 0.1 * final
    )  # as step_info joins them
    if np.isfinite(t10):
        colour, _ = BAND_STYLE["rise_s"]
        lo, hi, _ = bands["rise_s"]
        ax.plot(
            [t10 + lo, t10 + hi],
            [0.9 * final] * 2,
            color=colour,
            lw=5,
            alpha=0.8,
            solid_capstyle="butt",
            label=f"rise {lo:g}-{hi:g} s after the 10 % crossing, at 90 %",
        )
    (plo, phi, _), (olo, ohi, _) = bands["peak_s"], bands["overshoot"]
    colour, hatch = BAND_STYLE["peak_s"]
    ax.fill_between(
        [t0 + plo, t0 + phi],
        final + olo,
        final + ohi,
        facecolor=colour,
        alpha=0.3,
        hatch=hatch,
        edgecolor=colour,
        lw=0.8,
        label=f"peak {plo:g}-{phi:g} s, {olo:g}-{ohi:g} RPM over the final value",
    )
    settle_hi, width = bands["settling_s"][1], metrics["settling_band"]
    colour, hatch = BAND_STYLE["settling_s"]
    ax.fill_between(
        [t0 + settle_hi, end],
        final - width,
        final + width,
        facecolor=colour,
        alpha=0.15,
        hatch=hatch,
        edgecolor=colour,
        lw=0,
        label=f"settled within ±{width:.2f} RPM of the final value from {settle_hi:g} s",
    )
    slo, shi, _ = bands["steady_error"]
    ax.hlines(
        [ref + slo, ref + shi],
        0.8 * end,
        end,
        colors=BAND_STYLE["steady_error"][0],
        linestyles=":",
        lw=1.4,
        label=f"steady error {slo:+g} to {shi:+g} RPM of the reference",
    )


def _first_sample(ax, t0: float, ref: float) -> None:
    """Hatch the time before the earliest first published sample, one revolution at ``ref`` RPM
    after the command at ``t0`` s (listing 4.12), and annotate it."""
    colour, hatch = BAND_STYLE["first_sample"]
    earliest = t0 + 60.0 / ref
    ax.axvspan(
        t0,
        earliest,
        facecolor="none",
        hatch=hatch,
        edgecolor=colour,
        alpha=0.35,
        lw=0,
        label=f"no published sample before {earliest - t0:.2f} s (one revolution, listing 4.12)",
    )
    ax.axvline(earliest, color=colour, lw=1.0, ls="-.")
    ax.annotate(
        f"earliest first sample\n{earliest - t0:.2f} s after the command",
        (earliest, 0.35 * ref),
        xytext=(6, 0),
        textcoords="offset points",
        fontsize=7,
        color="0.3",
        va="center",
    )


def plot(results: dict, out_dir: Path) -> list[Path]:
    """One PNG per run (``run<N>.png``); see the module docstring."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from amr_twin.experiments.runner.executor import save_figure

    paths = []
    for r in results["runs"]:
        driven = [(w, name) for w, name in enumerate(("left", "right")) if name in r["wheels"]]
        if not driven:
            continue
        fig, axes = plt.subplots(
            len(driven), 1, figsize=(11.5, 3.6 * len(driven)), sharex=True, squeeze=False
        )
        for ax, (w, name) in zip(axes[:, 0], driven):
            _panel(ax, r, results, w, name)
            ax.set(ylabel=f"{name} wheel |speed| (RPM)", xlim=(0, r["duration_s"]))
            ax.grid(alpha=0.3)
            ax.legend(fontsize=6.5, loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0.0)
        axes[0, 0].set_title(f"Run {r['run']}: {r['title']}")
        axes[-1, 0].set_xlabel("time (s)")
        if results.get("firmware") != "improved":
            fig.text(0.01, 0.005, CAPTION, fontsize=7.5, color="0.3", va="bottom", wrap=True)
        fig.tight_layout(rect=(0, 0.05 if results.get("firmware") != "improved" else 0, 1, 1))
        path = Path(out_dir) / f"run{r['run']}.png"
        save_figure(fig, path)
        paths.append(path)
    return paths
