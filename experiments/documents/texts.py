"""The texts of the documents' generated blocks, each written from a committed result
(:mod:`amr_twin.experiments.documents.figures` runs the experiments and rewrites the blocks;
chapter 5's texts: :mod:`.chapter5_texts`).

Each function takes the committed data (the calibration's report, the fault study's, the payload
sweep's and the fusion seeds' in ``experiments/<name>/reference/``) and returns the block's
markdown; a claim that depends on a number (a timing met) is decided from it, so the text stays
true when the number moves.
"""

from __future__ import annotations

import math


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
