"""What ``amr-twin experiment umbmark`` writes: ``metrics.json``, ``report.md``, the Borenstein plot
``borenstein.png`` (each run's return error, both clusters and their centres of gravity, before and
after the calibration, a panel per seed), ``emax.png`` (E_max,syst per seed before and after) and
``calibration/seed<N>.yaml`` (the odometry node's calibration,
:mod:`amr_twin.controllers.odometry_calibration`).

Figures are in the UMBmark sense: a seed's *reduction* is E_max,syst before over after; a phase's
*scatter* is the RMS distance of the runs from their cluster's centre of gravity (the larger of the
two directions), and so is each part's. The *non-systematic spread* is the scatter of the part
Borenstein and Feng's list of error sources calls non-systematic, what the wheels do on the floor
(here the tyres' slip); the odometry's sampling part (the encoder's limited resolution and sampling
rate, systematic sources in that list, which no calibration removes) is reported beside it. Data
come from
:mod:`.seeds`.
"""

from __future__ import annotations

import math
from dataclasses import asdict
from pathlib import Path

import numpy as np

from amr_twin.controllers.odometry_calibration import text as calibration_text
from amr_twin.experiments.runner.executor import write_json, write_text
from amr_twin.experiments.fusion.seeds import spread
from amr_twin.experiments.fusion.seeds_report import cell, seed_text
from amr_twin.experiments.umbmark.experiment import Umbmark
from amr_twin.experiments.umbmark.plot import plot_borenstein, plot_emax
from amr_twin.experiments.umbmark.seeds import Phase, SeedResult

PARTS = (
    ("node", "odometry node (UMBmark's error)"),
    ("wheels", "geometry + slip (true wheel angles, the odometry's geometry)"),
    ("slip", "tyre slip (true wheel angles, true geometry)"),
    ("sampling", "the odometry's sampling of the speeds"),
)


def _umbmark(u: Umbmark) -> dict:
    d = asdict(u)
    d["alpha_deg"], d["beta_deg"] = math.degrees(u.alpha_rad), math.degrees(u.beta_rad)
    return d


def _phase(p: Phase) -> dict:
    runs = [
        {
            **asdict(r),
            "error_m": r.error_m,
            "wheels_error_m": r.wheels_error_m,
            "slip_error_m": r.slip_error_m,
        }
        for r in p.runs
    ]
    return {**{name: _umbmark(getattr(p, name)) for name, _ in PARTS}, "runs": runs}


def seed_data(r: SeedResult, cfg) -> dict:
    """One seed's JSON-ready figures."""
    return {
        "seed": r.seed,
        "tyres": r.tyres,
        "robot": r.robot.as_dict(cfg),
        "cpu_s": r.cpu_s,
        "before": _phase(r.before),
        "calibration": None if r.calibration is None else asdict(r.calibration),
        "after": None if r.after is None else _phase(r.after),
        "reduction": r.reduction,
    }


def summary(results: list[SeedResult], rigid: list[SeedResult] | None) -> dict:
    """Reductions and spreads over the seeds (:func:`~.fusion.seeds.spread`: mean, sd, min, max)."""
    before = [r.before.node.e_max_syst_m for r in results]
    out = {
        "e_max_syst_before_m": spread(before),
        "spread_before_m": spread([r.before.node.e_nonsyst_rms_m for r in results]),
        "slip_spread_before_m": spread([r.before.slip.e_nonsyst_rms_m for r in results]),
        "sampling_spread_before_m": spread([r.before.sampling.e_nonsyst_rms_m for r in results]),
        "sampling_e_max_syst_m": spread([r.before.sampling.e_max_syst_m for r in results]),
        "slip_e_max_syst_m": spread([r.before.slip.e_max_syst_m for r in results]),
        "geometry_and_slip_e_max_syst_m": spread([r.before.wheels.e_max_syst_m for r in results]),
    }
    if results[0].after is not None:
        after = [r.after.node.e_max_syst_m for r in results]
        factors = [r.reduction for r in results]
        out.update(
            e_max_syst_after_m=spread(after),
            spread_after_m=spread([r.after.node.e_nonsyst_rms_m for r in results]),
            reduction=spread(factors),
            reduction_median=float(np.median(factors)),
            reduction_of_means=float(np.mean(before) / np.mean(after)),
            seeds_reduced=sum(1 for f in factors if f > 1.0),
        )
    if rigid:
        out["rigid_spread_before_m"] = spread([r.before.node.e_nonsyst_rms_m for r in rigid])
        out["rigid_slip_spread_before_m"] = spread([r.before.slip.e_nonsyst_rms_m for r in rigid])
        out["rigid_sampling_spread_before_m"] = spread(
            [r.before.sampling.e_nonsyst_rms_m for r in rigid]
        )
        out["rigid_e_max_syst_before_m"] = spread([r.before.node.e_max_syst_m for r in rigid])
    return out


def markdown(data: dict) -> str:
    """The report's text."""
    s, m = data["summary"], data["meta"]
    mm = lambda v: f"{1e3 * v:.1f}"  # noqa: E731
    lines = [
        f"# UMBmark on the twin: seeds {seed_text(m['seeds'])}",
        "",
        f"{m['runs']} squares of {m['side_m']:g} m clockwise and {m['runs']} counter-clockwise "
        f"per seed and phase; "
        f"brush tyres {'on' if m['tyres'] else 'off (rigid contact)'}, the floor's friction field "
        f"{('on' if m['floor_field'] else 'off') if m['tyres'] else ''}"
        f"{'' if m['tyres'] else 'without effect (rigid contact)'}, "
        "improved firmware; each square driven to its corners and headings by the robot's "
        "odometry; "
        "each seed the robot the fusion experiment "
        "draws (tyre radii, track, hall sensors). E_max,syst: the larger distance of the two "
        "centres of "
        "gravity of the return errors from the origin; spread: the RMS distance of a direction's "
        "runs from "
        "its centre of gravity (the larger direction). All in mm.",
        "",
        f"- E_max,syst before calibration: {_mm_cell(s['e_max_syst_before_m'])}",
    ]
    if "e_max_syst_after_m" in s:
        lines += [
            f"- E_max,syst after: {_mm_cell(s['e_max_syst_after_m'])}; reduction per seed "
            f"{cell(s['reduction'], 1)}, median {s['reduction_median']:.1f}, of the means "
            f"{s['reduction_of_means']:.1f}; reduced on {s['seeds_reduced']} of "
            f"{len(m['seeds'])} seeds "
            "(Borenstein and Feng report about an order of magnitude on real robots)"
        ]
    rigid = "rigid_spread_before_m" in s
    lines.append(
        f"- non-systematic spread (the wheels on the floor: the tyres' slip) before: "
        f"{_mm_cell(s['slip_spread_before_m'], 3)}"
        + (
            f"; with the tyre model off (rigid contact, the same robots and run seeds): "
            f"{_mm_cell(s['rigid_slip_spread_before_m'], 3)}"
            if rigid
            else ""
        )
    )
    lines.append(
        f"- the odometry's sampling part (the 90-edge encoder's resolution and the 10 Hz samples: "
        f"systematic sources in Borenstein and Feng's list, not removed by the calibration): "
        f"{_mm_cell(s['sampling_spread_before_m'])}"
        + (f"; rigid contact: {_mm_cell(s['rigid_sampling_spread_before_m'])}" if rigid else "")
    )
    lines.append(
        f"- scatter of the return errors (all parts) before: {_mm_cell(s['spread_before_m'])}"
        + (f"; after: {_mm_cell(s['spread_after_m'])}" if "spread_after_m" in s else "")
        + (
            f"; rigid contact: {_mm_cell(s['rigid_spread_before_m'])}, E_max,syst "
            f"{_mm_cell(s['rigid_e_max_syst_before_m'])}"
            if rigid
            else ""
        )
    )
    lines += [
        f"- parts of E_max,syst before (UMBmark of each part's return errors): geometry + slip "
        f"{_mm_cell(s['geometry_and_slip_e_max_syst_m'])}, of which tyre slip "
        f"{_mm_cell(s['slip_e_max_syst_m'])}; "
        f"the odometry's sampling {_mm_cell(s['sampling_e_max_syst_m'])}",
        "",
        "| seed | radii L, R mm | track mm | E_max,syst before | after | reduction | E_d | E_b | "
        "scatter before | "
        "after | sampling part | slip part |",
        "|---|" + "---|" * 11,
    ]
    for d in data["per_seed"]:
        rb, b, a = d["robot"], d["before"], d["after"]
        lines.append(
            f"| {d['seed']} | {1e3 * rb['radius_error_left_m']:+.2f}, "
            f"{1e3 * rb['radius_error_right_m']:+.2f} "
            f"| {1e3 * rb['separation_error_m']:+.2f} | {mm(b['node']['e_max_syst_m'])} | "
            + (f"{mm(a['node']['e_max_syst_m'])} | {d['reduction']:.1f} | " if a else "- | - | ")
            + f"{b['node']['e_d']:.6f} | {b['node']['e_b']:.5f} | "
            f"{mm(b['node']['e_nonsyst_rms_m'])} | "
            + (f"{mm(a['node']['e_nonsyst_rms_m'])} | " if a else "- | ")
            + f"{mm(b['sampling']['e_max_syst_m'])} | {mm(b['slip']['e_max_syst_m'])} |"
        )
    lines += [
        "",
        "E_d and E_b are Borenstein's correction factors (the right over the left wheel's "
        "effective "
        "diameter; the effective over the nominal wheelbase); `calibration/seed<N>.yaml` holds "
        "the radii "
        "and wheelbase the odometry node used for the second squares (`amr-twin run --odometry "
        "FILE`).",
        "",
        "![Borenstein plot](borenstein.png)",
        "",
        "![E_max,syst per seed](emax.png)",
        "",
    ]
    return "\n".join(lines)


def _mm_cell(s: dict, decimals: int = 1) -> str:
    return cell({k: (v if k == "n" or v is None else 1e3 * v) for k, v in s.items()}, decimals)


def write(
    results: list[SeedResult], rigid: list[SeedResult] | None, cfg, meta: dict, out: Path
) -> dict:
    """Write the report files into ``out``; return the JSON data."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    data = {
        "meta": meta,
        "summary": summary(results, rigid),
        "per_seed": [seed_data(r, cfg) for r in results],
        "rigid_per_seed": [seed_data(r, cfg) for r in rigid] if rigid else None,
    }
    write_json(out / "metrics.json", data)
    for r in results:
        if r.calibration is not None:
            (out / "calibration").mkdir(exist_ok=True)
            write_text(
                out / "calibration" / f"seed{r.seed}.yaml",
                calibration_text(
                    r.calibration,
                    "The wheel odometry's calibration from UMBmark (amr-twin run --odometry FILE).",
                ),
            )
    plot_borenstein(data, out / "borenstein.png")
    plot_emax(data, out / "emax.png")
    write_text(out / "report.md", markdown(data))
    return data
