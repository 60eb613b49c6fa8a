"""The fault study's outputs: ``faults.md`` (the document), ``faults.json`` and
``img/faults_<case>.png``.

The committed page (:data:`PAGE`) and measures (:data:`COMMITTED_JSON`) are rewritten by
``python -m amr_twin.experiments.documents.figures``. The outputs hold no wall time: the same
code gives the same files, and a change of the plant shows as a diff.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np

from amr_twin.sim.faults import KINDS, kind_names, parse_fault
from amr_twin.recording.run_summary import json_ready
from amr_twin.experiments.runner.executor import save_figure, write_text
from amr_twin.experiments.faults.experiment import FAULT_T_S, FIRMWARES, SCENARIO, STOP_T_S
from amr_twin.model.paths import ROOT

REFERENCE_RPM = 38.197  # linear 0.5 m/s: 0.5 / (2 pi 0.125) * 60
COMMITTED_JSON = ROOT / "experiments" / "faults" / "reference" / "faults.json"
"""The committed measures the documents quote."""
PAGE = ROOT / "docs" / "reference" / "faults.md"
"""The committed page, written from :data:`COMMITTED_JSON`; its figures are in ``docs/img/``."""


def _slug(case: str) -> str:
    return (
        case.replace("@", "_at_")
        .replace(":", "_")
        .replace(",", "_")
        .replace("=", "")
        .replace(".", "p")
    )


def plot(results: dict, out: Path) -> list[Path]:
    """One figure per case: wheel speeds (true, published) and the path, per firmware, against the
    baseline."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    raw, paths = results["raw"], []
    for case in results["cases"]:
        fault = parse_fault(case)
        fig, axes = plt.subplots(2, 2, figsize=(10, 6.2), gridspec_kw={"width_ratios": [2.2, 1]})
        for row, fw in enumerate(FIRMWARES):
            r, base = raw[(case, fw)], raw[(None, fw)]
            ax = axes[row, 0]
            end = fault.until_s if fault.until_s is not None else r["t_s"][-1]
            ax.axvspan(fault.t_s, end, color="0.85", label="fault")
            ax.axvline(STOP_T_S, color="k", lw=0.8, ls=":", label="stop sent")
            for w, (name, color) in enumerate((("left", "tab:blue"), ("right", "tab:orange"))):
                ax.plot(r["t_s"], r["true_rpm"][:, w], color=color, lw=1.2, label=f"{name} true")
                pub = r["published"][w]
                if len(pub):
                    ax.plot(
                        pub[:, 0],
                        pub[:, 1],
                        "o",
                        ms=2.5,
                        color=color,
                        alpha=0.7,
                        label=f"{name} published",
                    )
            ax.axhline(REFERENCE_RPM, color="0.4", lw=0.6, ls="--")
            ax.set_ylim(-5, max(70.0, min(200.0, float(np.nanmax(r["true_rpm"])) + 5)))
            ax.set_ylabel(f"{fw}\nwheel speed, RPM")
            ax.grid(alpha=0.3)
            ax2 = axes[row, 1]
            ax2.plot(base["pose"][:, 0], base["pose"][:, 1], "--", color="0.5", label="no fault")
            ax2.plot(r["pose"][:, 0], r["pose"][:, 1], color="tab:red", label="with the fault")
            k = np.searchsorted(r["t_s"], fault.t_s)
            ax2.plot(*r["pose"][min(k, len(r["pose"]) - 1), :2], "kx", label="fault")
            ax2.set_aspect("equal", adjustable="datalim")
            ax2.grid(alpha=0.3)
            ax2.set_ylabel("y, m")
        axes[0, 0].legend(loc="upper right", fontsize=7, ncol=3)
        axes[0, 1].legend(loc="best", fontsize=7)
        axes[1, 0].set_xlabel("time, s")
        axes[1, 1].set_xlabel("x, m")
        fig.suptitle(f"--fault {case}", fontsize=11)
        fig.tight_layout()
        path = Path(out) / "img" / f"faults_{_slug(case)}.png"
        save_figure(fig, path, dpi=72)
        paths.append(path)
    return paths


def _f(value, fmt: str = ".1f") -> str:
    if value is None or (isinstance(value, float) and not math.isfinite(value)):
        return "-"
    text = format(value, fmt)
    return text[1:] if text.startswith("-") and not text.strip("-0.") else text  # no "-0.0"


def _pair(rows: dict, key) -> tuple:
    return tuple(key(rows[fw]) for fw in FIRMWARES)


def _reading(case: str, rows: dict) -> str:
    """What the measurements say, case by case (each number from this run)."""
    fa, im = rows["faithful"], rows["improved"]
    L = lambda r, k: r["wheels"]["left"][k]  # noqa: E731
    kind = parse_fault(case).kind
    if kind == "hall-dead" and case.endswith(":a"):
        return (
            f"With one of three hall sensors stuck the SC line changes 60 times per revolution, "
            f"not 90. "
            f"The faithful firmware, timing 90 changes per sample, publishes "
            f"{_f(L(fa, 'published_last_rpm'))} RPM "
            f"for a wheel turning at {_f(L(fa, 'true_during_rpm'))} RPM (2/3); its PI corrects "
            f"once per sample by "
            f"Ki*T = 0.03 of the error and the wheel stays at {_f(L(fa, 'true_during_rpm'))} "
            f"RPM. The improved "
            f"firmware also reads 2/3 of the speed, every 20 ms, and speeds the wheel up to "
            f"{_f(L(im, 'true_during_rpm'))} RPM: the robot ends {_f(im['end_offset_m'], '.2f')} "
            f"m and "
            f"{_f(im['end_heading_offset_deg'], '.0f')} deg from its fault-free run."
        )
    if kind == "hall-dead":
        return (
            f"The left SC line goes silent. The faithful firmware publishes "
            f"{L(fa, 'published_during')} left "
            f"speeds after the fault: its PI for that wheel only runs after a completed sample, "
            f"so the left "
            f"duty stays at {L(fa, 'pwm_before_stop')} counts and the wheel keeps turning open "
            f"loop at "
            f"{_f(L(fa, 'true_during_rpm'))} RPM; the motion looks normal "
            f"({_f(fa['end_offset_m'], '.2f')} m from the fault-free run) while the PC sees no "
            f"speed. The "
            f"improved firmware reads the silent wheel as stopped 150 ms later, publishes 0 and "
            f"raises its "
            f"command: the left wheel runs away to {_f(L(im, 'true_during_rpm'))} RPM (reference "
            f"{REFERENCE_RPM:.1f}) and the robot turns "
            f"{_f(abs(im['end_heading_offset_deg']), '.0f')} deg off its "
            f"course before the stop. Neither firmware checks that a driven wheel produces edges."
        )
    if kind == "hall-chatter":
        return (
            f"Spurious pulses add changes the firmwares count as rotation. The faithful firmware "
            f"completes its "
            f"90-change samples sooner ({L(fa, 'published_during')} left samples during the "
            f"fault instead of about "
            f"2), the last at {_f(L(fa, 'published_last_rpm'))} RPM; its PI, clamped at zero "
            f"integral and with Kp = 0.001, barely moves the duty "
            f"({_f(L(fa, 'true_during_rpm'))} RPM). The "
            f"improved firmware believes the wheel too fast and slows it to "
            f"{_f(L(im, 'true_during_rpm'))} RPM: "
            f"the robot ends {_f(abs(im['end_heading_offset_deg']), '.0f')} deg off its course."
        )
    if kind == "motor-stall":
        return (
            f"The jammed left wheel stops ({_f(L(fa, 'true_during_rpm'))} and "
            f"{_f(L(im, 'true_during_rpm'))} "
            f"RPM at the end of the jam) while the right one drives on: the robot pivots and ends "
            f"{_f(abs(fa['end_heading_offset_deg']), '.0f')} deg (faithful) and "
            f"{_f(abs(im['end_heading_offset_deg']), '.0f')} deg (improved) off its course. "
            f"Neither firmware "
            f"notices the stall or stops the other wheel; both resume the left wheel when the "
            f"jam clears "
            f"({_f(L(fa, 'true_before_stop_rpm'))} and {_f(L(im, 'true_before_stop_rpm'))} RPM "
            f"before the stop)."
        )
    if kind == "wheel-lifted":
        lifted = (
            f"The lifted wheel spins freely at {_f(L(fa, 'true_during_rpm'))} RPM (faithful) and "
            f"{_f(L(im, 'true_during_rpm'))} RPM (improved). "
        )
        if max(fa["end_offset_m"], im["end_offset_m"]) < 0.05:
            return lifted + (
                "The robot keeps its course: nothing resists its rolling, so at constant speed the "
                "one wheel still on the ground needs no force and makes no turning moment."
            )
        return lifted + (
            f"Only the right wheel drives, against the rolling resistance of the casters and of "
            f"itself: the robot turns {_f(abs(fa['end_heading_offset_deg']), '.0f')} deg "
            f"(faithful) "
            f"and {_f(abs(im['end_heading_offset_deg']), '.0f')} deg (improved) towards the lifted "
            "side during the 2 s, and neither firmware can tell: the lifted wheel's speed is "
            "what it commanded."
        )
    if kind == "rosserial-loss" and "0.3" not in case:
        return (
            f"With the link cut the stop sent at {STOP_T_S:g} s never arrives. Neither firmware "
            f"has a "
            f"watchdog on the link: the faithful one drives on at "
            f"{_f(L(fa, 'true_before_stop_rpm'))} RPM and "
            f"the robot covers {_f(fa['moved_after_stop_m'], '.2f')} m after the stop (improved: "
            f"{_f(im['moved_after_stop_m'], '.2f')} m; fault-free: "
            f"{_f(fa['baseline_moved_after_stop_m'], '.2f')} m), "
            f"still moving at the end of the run. The PC receives no wheel speed either "
            f"({L(fa, 'published_during')} and {L(im, 'published_during')} left samples)."
        )
    if kind == "rosserial-loss":
        return (
            f"30 % of the frames are lost (seeded). The wheel speeds reaching the PC thin out "
            f"({L(fa, 'published_during')} faithful and {L(im, 'published_during')} improved "
            f"left samples "
            f"during the fault); with this seed the stop frame arrived "
            f"({'stopped' if fa['stopped_at_end'] and im['stopped_at_end'] else 'NOT stopped'} "
            f"at the end). A "
            f"lost stop is the previous case: nothing on the Arduino repeats or times out a "
            f"command."
        )
    if kind == "rosserial-latency":
        return (
            f"Every frame arrives 250 ms late: the stop takes effect 250 ms later and the robot "
            f"ends "
            f"{_f(fa['end_offset_m'], '.2f')} m (faithful) and {_f(im['end_offset_m'], '.2f')} m "
            f"(improved) "
            f"further than without the delay; the published speeds reach the PC 250 ms older."
        )
    if kind == "lidar-dead":
        return (
            f"The firmware does not read the LiDAR: the motion is unchanged "
            f"({_f(fa['end_offset_m'], '.2f')} m). "
            f"No scan is published after the fault ({fa['scan_published_after']} scans): a "
            f"consumer (SLAM, "
            f"LiDAR odometry) has to detect the silence itself."
        )
    if kind == "imu-stuck":
        return (
            f"The firmware does not read the IMU: the motion is unchanged. imu/data_raw keeps "
            f"its 100 Hz "
            f"rate ({fa['imu_published_after']} messages after the fault) with fresh stamps but "
            f"{fa['imu_distinct_after']} distinct reading(s): only a plausibility check (a gyro "
            f"that never "
            f"changes while the wheels turn) reveals it."
        )
    if kind == "battery-sag":
        return (
            f"The terminal voltage falls to {_f(fa['min_battery_v'])} V. The drivers' output "
            f"falls with it: the "
            f"faithful firmware's PI, acting once per revolution with Ki*T = 0.03, leaves the "
            f"wheels at "
            f"{_f(L(fa, 'true_during_rpm'))} RPM until the stop; the improved firmware's 50 Hz "
            f"PI holds "
            f"{_f(L(im, 'true_during_rpm'))} RPM (duty {L(im, 'pwm_before_stop')} counts before "
            f"the stop)."
        )
    if kind in ("battery-cut", "estop"):
        what, back = (
            ("the drivers lose their supply", "power returns")
            if kind == "battery-cut"
            else ("the e-stop relays open the phases", "the button is released")
        )
        return (
            f"For 2 s {what}: the wheels coast down to {_f(L(fa, 'true_during_rpm'))} RPM. "
            f"Neither firmware "
            f"knows (no feedback of the relay or supply state); their commands stay on and the "
            f"wheels come "
            f"back when {back}, the improved firmware overshooting to "
            f"{_f(L(im, 'true_peak_rpm'))} RPM "
            f"(its integral grew while the slowing wheels were still inside its 8 RPM band). The "
            f"robot ends {_f(fa['end_offset_m'], '.2f')} m and "
            f"{_f(im['end_offset_m'], '.2f')} m from its fault-free runs."
        )
    return ""


def markdown(results: dict, images: str = "img") -> str:
    """``faults.md``: how to inject faults, the table of kinds, the study's table, plots and
    readings; ``images`` is the figures' folder relative to the page."""
    rows = {(r["fault"], r["firmware"]): r for r in results["rows"]}
    lines = [
        "# Fault injection",
        "",
        "The twin's faults are the robot's own: a sensor that stops or lies, a wheel that jams "
        "or leaves the "
        "ground, a serial link that drops or delays frames, a battery that sags or is cut, the "
        "e-stop. Inject "
        "them with `--fault KIND@T[:ARGS]` (repeatable) on `amr-twin run` and `amr-twin client`, "
        "or list them "
        "under `faults:` in a mission file. `T` is in seconds from the start; `ARGS` is the "
        "kind's parameter "
        "(bare or by name) and `for=S` to clear the fault after `S` seconds:",
        "",
        "```",
        "amr-twin run linear --speed-m-s 0.5 --duration-s 10 --world empty --fault "
        "hall-left-dead@3 --json",
        "amr-twin run --mission m.yaml --fault rosserial-loss@2:0.3,for=5 --fault estop@6:for=1",
        "```",
        "",
        "| kind | parameter (default) | what happens |",
        "|---|---|---|",
    ]
    for kind, spec in KINDS.items():
        names = [n for n in kind_names() if parse_fault(f"{n}@0").kind == kind]
        param = f"`{spec.param}` ({spec.default})" if spec.param else "-"
        lines.append(f"| {' / '.join(f'`{n}`' for n in names)} | {param} | {spec.summary} |")
    lines += [
        "",
        "The JSON summary of a run (`--json`) lists each fault under `faults` with its `effect`: "
        "per wheel "
        "the mean true speed before the fault and at the end, the peak after it, the speeds "
        "published after "
        "it and the last one, the PWM at the end; the distance driven after it; for sensor "
        "faults the "
        "messages published after it. Recordings carry them as `/twin/faults` (diagnostic_msgs/"
        "DiagnosticArray) in the `.mcap` and `events/faults` in the `.rrd`. The faults act "
        "through small "
        "hooks of the components (`amr_twin/sim/fault_injector.py`); random draws (frame loss, "
        "chatter) follow "
        "`--seed`.",
        "",
        "## What the firmwares do",
        "",
        f"Scenario: {SCENARIO}. `python -m amr_twin.experiments.documents.figures` regenerates "
        "the committed page and its figures (after any change of the plant or the firmwares). "
        f"Wheel speeds are true speeds in RPM (reference {REFERENCE_RPM:.1f}); *during* is the "
        f"mean over the "
        f"last 0.5 s of the fault (before the stop at {STOP_T_S:g} s); *offset* is the distance "
        f"and heading "
        "between the robot's final pose and its fault-free run's; *after stop* is the distance "
        "driven from "
        f"{STOP_T_S + 0.5:g} s on.",
        "",
        "| fault | firmware | left before / during | right during | left published during | "
        "offset m / deg "
        "| after stop m | stopped |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for case in results["cases"]:
        for fw in FIRMWARES:
            r = rows[(case, fw)]
            L, R = r["wheels"]["left"], r["wheels"]["right"]
            lines.append(
                f"| `{case}` | {fw} | {_f(L['true_before_rpm'])} / {_f(L['true_during_rpm'])} | "
                f"{_f(R['true_during_rpm'])} | {L['published_during']} | "
                f"{_f(r['end_offset_m'], '.2f')} / "
                f"{_f(r['end_heading_offset_deg'], '.0f')} | "
                f"{_f(r['moved_after_stop_m'], '.2f')} | "
                f"{'yes' if r['stopped_at_end'] else '**no**'} |"
            )
    lines += [""]
    for case in results["cases"]:
        fault = parse_fault(case)
        lines += [
            f"### `{case}`",
            "",
            f"*What happens:* {KINDS[fault.kind].summary}.",
            "",
            _reading(case, {fw: rows[(case, fw)] for fw in FIRMWARES}),
            "",
            f"![{case}]({images}/faults_{_slug(case)}.png)",
            "",
        ]
    return "\n".join(lines)


def measures(results: dict) -> dict:
    """What ``faults.json`` holds: the scenario, the fault and stop times (s) and the rows."""
    data = {
        "scenario": SCENARIO,
        "fault_t_s": FAULT_T_S,
        "stop_t_s": STOP_T_S,
        "rows": results["rows"],
    }
    return data


def _json_text(data: dict) -> str:
    return json.dumps(json_ready(data), indent=2, allow_nan=False) + "\n"


def report(results: dict, out: Path) -> dict:
    """Write ``faults.md`` and ``faults.json`` (the measures) in ``out``; return the measures."""
    data = measures(results)
    write_text(Path(out) / "faults.json", _json_text(data))
    write_text(Path(out) / "faults.md", markdown(results))
    return data


def committed_write(results: dict) -> dict:
    """Write :data:`COMMITTED_JSON`, :data:`PAGE` and the figures in ``docs/img/``; return the
    measures."""
    plot(results, ROOT / "docs")
    data = measures(results)
    write_text(COMMITTED_JSON, _json_text(data))
    write_text(PAGE, markdown(results, images="../img"))
    return data
