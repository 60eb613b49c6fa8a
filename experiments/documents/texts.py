"""The texts of the documents' generated blocks, each written from a committed result
(:mod:`amr_twin.experiments.documents.figures` runs the experiments and rewrites the blocks).

Each function takes the committed data (the chapter 5 scorecard, the calibration's report, the
fault study's, the payload sweep's and the fusion seeds' in ``experiments/<name>/reference/``)
and returns the block's markdown; a claim that depends on a number (the right wheel overshooting
more, a timing met) is decided from it, so the text stays true when the number moves.
"""

from __future__ import annotations

import math

from amr_twin.experiments.chapter5.criteria import BANDS


def _rpm(value: float) -> str:
    return f"{value:+.2f}"


def _counts(checks: dict, prefix: str = "") -> dict[str, tuple[int, int]]:
    """Per metric of :data:`BANDS`: (passed, checks) among ``checks`` whose metric part starts
    ``prefix``."""
    out: dict[str, list[int]] = {}
    for key, c in checks.items():
        run, wheel, *rest = key.split(".")
        metric = ".".join(rest)
        if prefix and not metric.startswith(prefix) or not prefix and metric.startswith("true."):
            continue
        n = out.setdefault(metric[len(prefix) :], [0, 0])
        n[0] += _passes(checks, key)
        n[1] += 1
    return {k: (p, n) for k, (p, n) in out.items()}


def chapter5_summary(card: dict) -> str:
    """``docs/reference/results.md``'s chapter 5 paragraph, from the scorecard."""
    c, pub, true = card["checks"], _counts(card["checks"]), _counts(card["checks"], "true.")
    timing = ("delay_s", "rise_s", "peak_s", "settling_s")
    timed = [sum(true[m][i] for m in timing) for i in (0, 1)]
    missed_steady = [
        k
        for k, v in c.items()
        if k.endswith(".steady_error")
        and ".true." not in k
        and not v["band"][0] <= v["twin"] <= v["band"][1]
    ]
    missed = ", ".join(
        f"run {k.split('.')[0][3:]} {k.split('.')[1]} {_rpm(c[k]['twin'])}" for k in missed_steady
    )
    left, right = c["run1.left.overshoot"]["twin"], c["run2.right.overshoot"]["twin"]
    more = (
        "overshoots more than the left, as in §5.1.3"
        if right > left + 0.5
        else "does not overshoot more than the left"
    )
    met = sum(pub[m][0] for m in timing)
    times = (
        "none of the delay, rise, peak and settling times is met"
        if met == 0
        else f"{met} of {sum(pub[m][1] for m in timing)} delay, rise, peak and settling times "
        f"are met"
    )
    where = "; ".join(
        f"run {rw[0][3:]} {rw[1]}: "
        + ", ".join(m[:-2] for m in timing if _passes(c, f"{rw[0]}.{rw[1]}.true.{m}"))
        for rw in _runs(c)
        if any(_passes(c, f"{rw[0]}.{rw[1]}.true.{m}") for m in timing)
    )
    return (
        f"Chapter 5 (`amr-twin experiment chapter5`, faithful firmware, calibrated plant), "
        f"scored with the "
        f"definitions of the thesis' fig. 5.3 (Ogata's: overshoot above the final value, the "
        f"steady offset "
        f"judged on its own; `docs/explanation/validation.md`): on the published samples "
        f"**{card['passed']} of "
        f"{card['checks_total']} checks pass**. The steady offset lies within the faithful PI's "
        f"4 RPM dead "
        f"zone on {pub['steady_error'][0]} of {pub['steady_error'][1]} wheels (runs 1 and 2, "
        f"76.39 RPM: left "
        f"{_rpm(c['run1.left.steady_error']['twin'])}, right "
        f"{_rpm(c['run2.right.steady_error']['twin'])} RPM)"
        + (f", not on {missed}" if missed else "")
        + f"; the overshoot is in its band on {pub['overshoot'][0]} of "
        f"{pub['overshoot'][1]}, and the right wheel {more} (runs 1 and 2: {left:.2f} left, "
        f"{right:.2f} RPM "
        f"right, against §5.1.3's 0-2 and 4 RPM); {times}: the firmware publishes once per wheel "
        f"revolution, so "
        f"its first sample comes a revolution after the command (0.8 s at 76 RPM, plus the "
        f"ramp), which puts the "
        f"delay, rise and peak of the steps up to 75 RPM out of any plant's reach "
        f"(`docs/explanation/validation.md`) and "
        f"leaves the rest to the ramp and the timer; and {card['oscillation_published_passed']} "
        f"of the 4 oscillation "
        f"comparisons holds. The true wheel speed (100 Hz, which the thesis could not see) "
        f"against the same "
        f"bands passes {card['true_passed']} of {card['true_checks_total']}, its timings "
        f"{timed[0]} of {timed[1]} "
        f"("
        + ", ".join(f"{m[:-2]} {true[m][0]}" for m in timing)
        + f" of 14 each; {where}). Run 1: delay "
        f"{c['run1.left.true.delay_s']['twin']:.2f} s, rise "
        f"{c['run1.left.true.rise_s']['twin']:.2f} s, peak "
        f"{c['run1.left.true.peak_s']['twin']:.2f} s, settling "
        f"{c['run1.left.true.settling_s']['twin']:.2f} s "
        f"against 0.5, 1.0, 1.1 and at most 1.3 s. Every check's value is committed "
        f"(`tests/chapter5_scorecard.json`), and a change that takes one further from the thesis "
        f"fails the tests.\n"
    )


def _passes(checks: dict, key: str) -> bool:
    check = checks.get(key)
    return (
        check is not None
        and check["twin"] is not None
        and check["band"][0] <= check["twin"] <= check["band"][1]
    )


def _runs(checks: dict) -> list[tuple[str, str]]:
    """``(run<N>, wheel)`` of the scorecard, in run order."""
    return sorted({tuple(k.split(".")[:2]) for k in checks}, key=lambda rw: (int(rw[0][3:]), rw[1]))


def chapter5_table(card: dict) -> str:
    """docs/explanation/validation.md's table of every check: the twin's value, published and true,
    against its band."""
    c = card["checks"]
    metrics = list(dict.fromkeys(b.metric for b in BANDS))
    rows = _runs(c)
    lines = [
        f"Checks passed: **{card['passed']} of {card['checks_total']}** on the published samples "
        f"({card['checks_total'] - len(rows) * len(metrics)} of them the 20 kg oscillation "
        f"comparisons, "
        f"{card['oscillation_published_passed']} passed); the true speed against the same bands "
        f"{card['true_passed']} of {card['true_checks_total']}. Published / true, ✓ inside the "
        f"band:",
        "",
        "| run | wheel | " + " | ".join(metrics) + " |",
        "|---|---|" + "---|" * len(metrics),
    ]

    def cell(key: str) -> str:
        value = c[key]["twin"] if key in c else None
        return ("—" if value is None else f"{value:.2f}") + (" ✓" if _passes(c, key) else "")

    for run, wheel in rows:
        cells = [
            f"{cell(f'{run}.{wheel}.{m}')} / {cell(f'{run}.{wheel}.true.{m}')}" for m in metrics
        ]
        lines.append(f"| {run[3:]} | {wheel} | " + " | ".join(cells) + " |")
    bands = "; ".join(
        f"{b.metric} {b.low:g} – {b.high:g}"
        + (f" ({b.wheel})" if b.wheel != "any" else "")
        + ({"small": " ≤ 75 RPM", "large": " > 75 RPM"}.get(b.step_class, ""))
        for b in BANDS
    )
    return "\n".join(lines + ["", f"Bands: {bands}."]) + "\n"


def faults_summary(data: dict) -> str:
    """``docs/reference/results.md``'s fault paragraph, from the fault study's committed
    measures."""
    rows = {(r["fault"], r["firmware"]): r for r in data["rows"]}

    def left(case: str, fw: str, key: str = "true_during_rpm") -> float:
        return rows[(case, fw)]["wheels"]["left"][key]

    def turn(case: str, fw: str) -> float:
        return abs(rows[(case, fw)]["end_heading_offset_deg"])

    cut = "rosserial-loss@5"
    return (
        f"Faults (`amr-twin experiment faults`; the page: `docs/reference/faults.md`): each "
        f"kind injected at "
        f"{data['fault_t_s']:g} s into a 0.5 m/s run that is told to stop at "
        f"{data['stop_t_s']:g} s, under both "
        f"firmwares. Neither firmware has a watchdog: with the rosserial link cut the stop never "
        f"arrives, and "
        f"the robot drives {rows[(cut, 'faithful')]['moved_after_stop_m']:.2f} m past it "
        f"(faithful; improved "
        f"{rows[(cut, 'improved')]['moved_after_stop_m']:.2f} m), still moving at the end. A "
        f"silent left hall "
        f"signal goes unnoticed by the faithful firmware (the wheel runs open loop at its last "
        f"duty while the "
        f"PC gets no speed) and makes the improved one run the wheel away to "
        f"{left('hall-left-dead@5', 'improved'):.1f} RPM (reference 38.2), turning the robot "
        f"{turn('hall-left-dead@5', 'improved'):.0f} degrees; chatter on the line slows it to "
        f"{left('hall-left-chatter@5:200', 'improved'):.1f} RPM. A 12 V battery sag leaves the "
        f"faithful "
        f"firmware's wheels at {left('battery-sag@5:12', 'faithful'):.1f} RPM, the improved one "
        f"holds "
        f"{left('battery-sag@5:12', 'improved'):.1f}. A jammed wheel pivots the robot "
        f"{turn('motor-left-stall@5:for=2', 'faithful'):.0f} (faithful) and "
        f"{turn('motor-left-stall@5:for=2', 'improved'):.0f} degrees (improved); a wheel lifted "
        f"for 2 s turns it "
        f"{turn('wheel-left-lifted@5:for=2', 'faithful'):.0f} and "
        f"{turn('wheel-left-lifted@5:for=2', 'improved'):.0f} degrees, unseen by either.\n"
    )


def calibration_summary(report: dict) -> str:
    """The calibration's figures (``models/amr/calibration.yaml``, ``amr-twin calibrate --no-fit
    --report``): each fitted value with its 1 sigma, and how well the gain-to-Ke ratio (the speed a
    duty count gives) is pinned: ``sqrt(a^2 + b^2 - 2 r a b)`` of the relative sigmas ``a``, ``b``
    and their correlation ``r``."""
    p, corr = report["parameters"], report["correlation"]
    keys = list(p)

    def ratio_pct(board: str, key: str) -> float:
        a, b = p[board]["sigma"] / p[board]["value"], p[key]["sigma"] / p[key]["value"]
        r = corr[keys.index(board)][keys.index(key)]
        return 100 * math.sqrt(max(0.0, a * a + b * b - 2 * r * a * b))

    def value(key: str, digits: int) -> str:
        return f"{p[key]['value']:.{digits}f} ± {p[key]['sigma']:.{digits}f}"

    r = min(
        abs(corr[keys.index("driver_left.gain")][keys.index("motor_left.ke_v_s_rad")]),
        abs(corr[keys.index("driver_right.gain")][keys.index("motor_right.ke_v_s_rad")]),
    )
    return (
        f"The calibration (`amr-twin calibrate --target thesis`: the bench point, the steady "
        f"speeds, the "
        f"overshoot and the true-speed timings; `models/amr/calibration.yaml`, chi^2 "
        f"{report['chi2']:.1f}) "
        f"reports each parameter with its uncertainty: driver gains "
        f"{value('driver_left.gain', 2)} left and "
        f"{value('driver_right.gain', 2)} right, Ke "
        f"{value('motor_left.ke_v_s_rad', 3)} and {value('motor_right.ke_v_s_rad', 3)} V s/rad, "
        f"each wheel's "
        f"gain and Ke correlated at {r:.2f} or more (their ratio, the speed per duty count, is "
        f"pinned within "
        f"{ratio_pct('driver_left.gain', 'motor_left.ke_v_s_rad'):.1f} % left and "
        f"{ratio_pct('driver_right.gain', 'motor_right.ke_v_s_rad'):.1f} % "
        f"right), dry friction {value('motor_left.friction_nm', 3)} and "
        f"{value('motor_right.friction_nm', 3)} "
        f"N m.\n"
    )


def payload_summary(data: dict) -> str:
    """``docs/reference/results.md``'s payload sweep paragraph, from :data:`PAYLOAD_JSON`."""
    low, energy = data["lowest_wheel"], data["center_energy_j_per_m"]
    answers = "; ".join(
        f"**{p}**: {s['answer']}"
        + (f"; with the improved firmware: {s['improved']['answer']}" if "improved" in s else "")
        for p, s in data["positions"].items()
    )
    return (
        f"Payload sweep (`amr-twin sweep payload --masses 0:60:10 --positions "
        f"{','.join(data['sweep']['positions'])} "
        f"--commands {','.join(data['sweep']['commands'])}`, {data['points']} points of 8 s; the "
        f"positions "
        f"limited by a runaway are run again with the improved firmware): the base tilts at most "
        f"{data['max_tilt_deg']:.1f} degrees, and the lowest drive-wheel load is "
        f"{low['dyn_min_wheel_n']:.0f} N "
        f"({low['mass_kg']:g} kg, {low['position']}, {low['command']}: "
        f"{low['dyn_min_wheel_mechanism']}; each "
        f"point's lowest load comes with its mechanism in `summary.md`). Each position's answer, "
        f"the cause of "
        f"its limit named: {answers}. A runaway is a limit of the speed control, not of the "
        f"motors' rating at "
        f"what the payload demands: with the load behind the axle the robot oversteers in the "
        f"clockwise turn, "
        f"and a firmware that does not hold the inner wheel's speed lets it pivot, the current "
        f"rising with it "
        f"(`docs/explanation/validation.md`). Energy per metre at 0.7 m/s, centre: "
        f"{energy['0']:.0f} J/m empty, "
        f"{energy['60']:.0f} J/m with 60 kg (pack and electronics).\n"
    )


SUMMARY_FUSION = ("ate_m", "ate_aligned_m", "rpe_trans_m", "rpe_rot_deg", "rms_yaw_err_deg")
"""The columns of ``docs/reference/results.md``'s fusion tables (``docs/explanation/fusion.md`` has
them all)."""


def fusion_table(data: dict, keys: tuple[str, ...] | None = None) -> str:
    """A route's table of architectures (mean ± sd (min-max) over the seeds), all metrics or
    ``keys``; with all, the map and UWB line and every seed's ATE
    (``docs/explanation/fusion.md``)."""
    from amr_twin.experiments.fusion.seeds_report import (
        METRICS,
        cell,
        per_seed_table,
        percent,
        table,
    )

    if keys is None:
        return (
            "\n".join(
                [
                    *table(data),
                    "",
                    f"Map from the LiDAR odometry, occupied cells within 2 cells of the "
                    f"world's walls: {cell(percent(data['map_within_tolerance_frac']), 1)} %. "
                    f"UWB exchanges "
                    f"with a wall in the tag-anchor line: "
                    f"{cell(percent(data['uwb_blocked_frac']), 1)} %.",
                    "",
                    *per_seed_table(data),
                ]
            )
            + "\n"
        )
    chosen = [m for m in METRICS if m[0] in keys]
    lines = [
        "| architecture | " + " | ".join(title for _, title, _ in chosen) + " |",
        "|---|" + "---|" * len(chosen),
    ]
    lines += [
        f"| {name} | " + " | ".join(cell(a[k], d) for k, _, d in chosen) + " |"
        for name, a in data["architectures"].items()
    ]
    return "\n".join(lines) + "\n"


ATTAINABLE_ROWS = (
    (
        "overshoot_right",
        "right overshoots 2-6 RPM and >= left + 1 (published), same order on the "
        "true speed, 4 of runs 3-8",
    ),
    ("tracking", "unloaded wheels in the 4 RPM dead zone"),
    ("duty_raised", "20 kg: the PI raises the duty on all 4 wheels of runs 7, 8"),
    ("oscillation", "20 kg: more oscillation in 3 of 4 comparisons, samples and true speed"),
)


def attainable_table(data: dict) -> str:
    """The committed chapter 5 attainability study (``experiments/chapter5/reference``): per
    finding, the plants of each seed where it holds, and the best figure reached over all of
    them."""
    seeds = data["seeds"]
    head = " | ".join(f"seed {k} ({v['samples']} plants)" for k, v in seeds.items())
    s = list(seeds.values())
    best = {
        "overshoot_right": f"right at most {max(v['best_right_overshoot_rpm'] for v in s):.2f} "
        f"RPM; right "
        f"minus left at most {max(v['best_right_minus_left_rpm'] for v in s):.2f}",
        "tracking": f"worst unloaded error "
        f"{min(v['least_worst_steady_error_rpm'] for v in s):.2f} RPM at best",
        "duty_raised": f"{max(v['most_raised_wheels'] for v in s)} of 4 wheels at most",
        "oscillation": f"{max(v['most_oscillating_more'] for v in s)} of 4 at most",
    }
    lines = [f"| finding | {head} | best figure reached |", "|---|" + "---|" * len(seeds) + "---|"]
    for key, text in ATTAINABLE_ROWS:
        lines.append(
            f"| {text} | " + " | ".join(str(v["held"][key]) for v in s) + f" | {best[key]} |"
        )
    lines.append("| all four | " + " | ".join(str(v["all"]) for v in seeds.values()) + " | |")
    pairs = sum(v["pairs"][p] for v in seeds.values() for p in v["pairs"])
    lines += [
        "",
        f"Pairs of findings holding together: {pairs} over "
        f"{sum(v['samples'] for v in seeds.values())} "
        "plants.",
    ]
    return "\n".join(lines) + "\n"
