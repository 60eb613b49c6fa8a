"""Two firmwares on the same runs, sample by sample: the emulated board against the faithful port.

:func:`compare` pairs the runs of two :func:`amr_twin.experiments.chapter5.experiment.run` results
(same run numbers) and, per driven wheel, the k-th published sample of one with the k-th of the
other (times and speeds), the true wheel speed and the PWM counts on the 100 Hz record grid.
:func:`markdown` renders the table of ``report.md``. Where the differences come from is
explained in docs/explanation/firmware.md ("The emulated board against the faithful port").

Acceptance: the last published samples within :data:`FINAL_RPM_TOL` and the first
published samples within :data:`FIRST_SAMPLE_TOL_S` of each other.

The emulated board is brought up to the loop's time every millisecond, so the loop samples the
physics every step, while with the Python ports it samples it at the firmware's own events and
the 10 ms record grid; the hall edges, interpolated between samples, then differ by up to about a
millisecond when a wheel starts from rest. The reference is therefore also run *paced*
(:func:`pace`: a synced no-op every :data:`PACE_US`), which leaves only the firmwares' differences.
"""

from __future__ import annotations

import numpy as np

FINAL_RPM_TOL = 1.5
"""Largest accepted difference of the last published speed, RPM."""

FIRST_SAMPLE_TOL_S = 0.05
"""Largest accepted difference of the first published sample's time, s."""

PACE_US = 1000
"""Physics sampling of a paced reference run, us (the emulated board's sync period)."""


def pace(twin, period_us: int = PACE_US) -> None:
    """Make ``twin``'s loop stop the physics every ``period_us`` (a synced event that does
    nothing)."""
    clock = twin.clock

    def tick() -> None:
        clock.schedule_in(period_us, tick)

    clock.schedule_in(period_us, tick)


def _wheel(raw_a: dict, raw_b: dict, w: int) -> dict:
    pa, pb = np.asarray(raw_a["published"][w]), np.asarray(raw_b["published"][w])
    n = min(len(pa), len(pb))
    out = {"samples": [int(len(pa)), int(len(pb))]}
    if n:
        dt, dv = pa[:n, 0] - pb[:n, 0], pa[:n, 1] - pb[:n, 1]
        out.update(
            first_t_s=[float(pa[0, 0]), float(pb[0, 0])],
            first_dt_ms=float(dt[0] * 1e3),
            first_drpm=float(dv[0]),
            max_abs_dt_ms=float(np.max(np.abs(dt)) * 1e3),
            max_abs_drpm=float(np.max(np.abs(dv))),
            final_rpm=[float(pa[-1, 1]), float(pb[-1, 1])],
            final_drpm=float(pa[-1, 1] - pb[-1, 1]),
        )
    m = min(len(raw_a["t_s"]), len(raw_b["t_s"]))
    tv = np.asarray(raw_a["true_rpm"])[:m, w] - np.asarray(raw_b["true_rpm"])[:m, w]
    pwm = np.asarray(raw_a["pwm_counts"])[:m, w] - np.asarray(raw_b["pwm_counts"])[:m, w]
    out.update(
        true_rms_drpm=float(np.sqrt(np.mean(tv**2))),
        true_max_abs_drpm=float(np.max(np.abs(tv))),
        true_final_drpm=float(tv[-1]),
        pwm_differs_pct=float(100 * np.mean(pwm != 0)),
        pwm_max_abs_diff=int(np.max(np.abs(pwm))),
    )
    ok = (
        n > 0
        and len(pa) > 0
        and len(pb) > 0
        and abs(out["final_drpm"]) <= FINAL_RPM_TOL
        and abs(out["first_dt_ms"]) <= FIRST_SAMPLE_TOL_S * 1e3
    )
    out["verdict"] = "pass" if ok else "fail"
    return out


def compare(
    runs_a: list[dict],
    runs_b: list[dict],
    firmware_a: str,
    firmware_b: str,
    paced: list[dict] | None = None,
) -> dict:
    """Differences of ``runs_a`` against ``runs_b`` (analysed chapter 5 runs with their ``raw``).

    ``paced``: the reference runs again, paced (:func:`pace`); each row then has ``paced``, the
    same differences against those.
    """
    by_number = {r["run"]: r for r in runs_b}
    paced_by_number = {r["run"]: r for r in paced or []}
    rows = []
    for ra in runs_a:
        rb = by_number.get(ra["run"])
        if rb is None:
            continue
        for w, name in enumerate(("left", "right")):
            if name not in ra["wheels"]:
                continue
            row = {
                "run": ra["run"],
                "wheel": name,
                "reference_rpm": ra["wheels"][name]["reference_rpm"],
                **_wheel(ra["raw"], rb["raw"], w),
            }
            if ra["run"] in paced_by_number:
                row["paced"] = _wheel(ra["raw"], paced_by_number[ra["run"]]["raw"], w)
            rows.append(row)
    worst = {
        key: max((abs(r[key]) for r in rows if key in r), default=None)
        for key in ("first_dt_ms", "max_abs_dt_ms", "max_abs_drpm", "final_drpm", "true_rms_drpm")
    }
    return {
        "firmware": firmware_a,
        "reference": firmware_b,
        "final_rpm_tolerance": FINAL_RPM_TOL,
        "first_sample_tolerance_s": FIRST_SAMPLE_TOL_S,
        "rows": rows,
        "worst": worst,
        "verdict": "pass" if rows and all(r["verdict"] == "pass" for r in rows) else "fail",
    }


def _n(value, digits: int = 2) -> str:
    return "—" if value is None else f"{value:.{digits}f}"


def _row(r: dict) -> str:
    last = "—" if "final_rpm" not in r else f"{r['final_rpm'][0]:.3f} / {r['final_rpm'][1]:.3f}"
    return (
        f"{r['samples'][0]} / {r['samples'][1]} | {_n(r.get('first_dt_ms'), 1)} | "
        f"{_n(r.get('first_drpm'), 3)} | "
        f"{_n(r.get('max_abs_dt_ms'), 1)} | {_n(r.get('max_abs_drpm'), 3)} | {last} | "
        f"{_n(r.get('final_drpm'), 3)} | "
        f"{_n(r['true_rms_drpm'], 3)} | {r['pwm_differs_pct']:.1f} | {r['verdict']} |"
    )


def markdown(comp: dict) -> list[str]:
    """The report section: one row per run and wheel (and the paced reference's table)."""
    lines = [
        f"`{comp['firmware']}` against `{comp['reference']}` on the same runs, sample by sample "
        f"(k-th "
        "published sample against k-th; true speed and PWM counts on the 100 Hz grid). Δ = "
        f"{comp['firmware']} − {comp['reference']}. Accepted: last published speeds within "
        f"{comp['final_rpm_tolerance']:g} RPM, first published samples within "
        f"{comp['first_sample_tolerance_s'] * 1e3:g} ms. Where the differences come from: "
        f"docs/explanation/firmware.md, "
        '"The emulated board against the faithful port".',
        "",
        "| run | wheel | ref RPM | samples | first sample Δt ms | first Δ RPM | max \\|Δt\\| ms | "
        "max \\|Δ\\| RPM | last RPM | last Δ RPM | true RMS Δ RPM | PWM differs % | verdict |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in comp["rows"]:
        lines.append(f"| {r['run']} | {r['wheel']} | {r['reference_rpm']:.2f} | " + _row(r))
    w = comp["worst"]
    lines += [
        "",
        f"**Verdict: {comp['verdict']}** — worst first-sample Δt {_n(w['first_dt_ms'], 1)} ms, "
        f"worst "
        f"last-sample Δ {_n(w['final_drpm'], 3)} RPM, worst sample Δ {_n(w['max_abs_drpm'], 3)} "
        f"RPM, "
        f"worst sample Δt {_n(w['max_abs_dt_ms'], 1)} ms.",
    ]
    paced = [r["paced"] for r in comp["rows"] if "paced" in r]
    if paced:

        def worst(key):
            return max((abs(p[key]) for p in paced if key in p), default=None)

        same = sum(p.get("samples", [0])[0] == p.get("samples", [0, 1])[1] for p in paced)
        lines += [
            "",
            f"Against `{comp['reference']}` *paced* (its loop stops the physics every {PACE_US} "
            f"us, as "
            "the emulated board's does, so both sample the physics at the same instants): worst "
            f"first-sample Δt {_n(worst('first_dt_ms'), 1)} ms, worst last-sample Δ "
            f"{_n(worst('final_drpm'), 3)} RPM, worst sample Δ {_n(worst('max_abs_drpm'), 3)} "
            f"RPM, worst "
            f"true-speed RMS Δ {_n(worst('true_rms_drpm'), 3)} RPM, equal sample counts in "
            f"{same} of "
            f"{len(paced)} rows: what is left is the firmwares' own difference.",
        ]
    if "timeline" in comp:
        tl = comp["timeline"]
        lines += [
            "",
            f"One wheel_Command {tl['command']} with the wheels at rest (no physics, so no "
            f"sample and no "
            "PI action): when each pin changes, the k-th change of each pin paired. The port "
            "acts when "
            "the link's frame ends (115200 baud); the board's time is that of the instruction "
            "that wrote "
            "the pin (its UART runs at 117647 baud: UBRR 16 with U2X).",
            "",
            "| wheel | pin | k | value port / board | port ms | board ms | board − port us |",
            "|---|---|---|---|---|---|---|",
        ]
        for r in tl["rows"]:
            if r["k"] is None:
                lines.append(
                    f"| {r['wheel']} | {r['pin']} | — | changes {r['value'][0]} / "
                    f"{r['value'][1]} | | | |"
                )
            else:
                lines.append(
                    f"| {r['wheel']} | {r['pin']} | {r['k']} | {r['value'][0]} / {r['value'][1]} | "
                    f"{r['t_port_ms']:.3f} | {r['t_board_ms']:.3f} | {r['dt_us']} |"
                )
    return lines
