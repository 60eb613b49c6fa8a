"""The eight step experiments of thesis chapter 5, measured and judged against the thesis.

:func:`run` simulates the runs (§5.1.1-5.1.4, :mod:`.runs`), :func:`plot` draws one figure per run
as in chapter 5, :func:`report` writes ``metrics.json`` (from the typed
:class:`.metrics.Chapter5Metrics`) and ``report.md``. The runs are
judged against the thesis by :mod:`.criteria` (published samples, settling band,
the 20 kg runs' oscillation).
The runs use the empty world (the warehouse walls would stop a 16 s straight run).

Recordings (``record_dir`` / ``mcap_dir`` of :func:`run`): one ``run<N>.rrd`` /
``run<N>.mcap`` per run (:mod:`amr_twin.recording.rerun_log`, :mod:`amr_twin.recording.mcap_log`),
written by the process that simulates the run to a temporary name of this process
(``.run<N>.rrd.<pid>.tmp``), renamed only once every run is done (with the caller's
:func:`~amr_twin.base.atomic_file.all_or_nothing` batch, if one is open) and removed if the
runs are interrupted or fail. Recording does not change the results.
"""

from __future__ import annotations

import time
from pathlib import Path

from amr_twin.experiments.chapter5 import payload
from amr_twin.experiments.chapter5.criteria import compare_oscillation
from amr_twin.experiments.chapter5.metrics import Chapter5Metrics, metrics
from amr_twin.experiments.chapter5.runs import RUNS, RunJob, RunSpec, analyse, simulate
from amr_twin.model.config import TwinConfig


def run(
    cfg: TwinConfig,
    jobs: int = 1,
    firmware: str = "faithful",
    runs: list[int] | None = None,
    duration_s: float | None = None,
    progress: bool = True,
    record_dir: Path | None = None,
    mcap_dir: Path | None = None,
    study: bool = True,
    reference_firmware: str | None = None,
) -> dict:
    """Simulate the chapter 5 runs and measure them.

    Parameters
    ----------
    cfg : the twin's parameters (payload as in the file; runs 7-8 set 20 kg).
    jobs : worker processes (1: in this process).
    firmware : "faithful", "improved", "avr" or "avr:SKETCH_DIR".
    runs : run numbers to do (default all eight).
    duration_s : override every run's duration, s (tests).
    progress : show a progress bar.
    record_dir : folder for one Rerun recording per run, ``run<N>.rrd`` (created; None: none).
    mcap_dir : folder for one MCAP file per run, ``run<N>.mcap`` (may be ``record_dir``).
    study : with the whole suite, also run §5.1.4's rolling-resistance study
        (:mod:`.payload`, 8 more runs).
    reference_firmware : also run this firmware (not recorded) and tabulate the differences
        sample by sample in ``"firmware_comparison"`` (:mod:`.firmware_comparison`); it is run
        twice: as is, and with the physics sampled every millisecond as the emulated board's
        loop samples it (:data:`~.firmware_comparison.PACE_US`), which separates the firmware's
        differences from the loop's.

    Returns
    -------
    dict : ``{"firmware", "wall_s", "sim_s", "runs": [per run], "comparisons": [...]}``.
    """
    from amr_twin.experiments.runner.executor import run_all

    specs = [s for s in RUNS if runs is None or s.number in runs]
    if not specs:
        raise ValueError(f"runs: {runs} selects none of 1..{len(RUNS)}")
    wall0 = time.perf_counter()
    from amr_twin.recording.rerun_capture import recording_folder

    folders = {
        kind: recording_folder(folder)
        for kind, folder in (("rrd", record_dir), ("mcap", mcap_dir))
        if folder is not None
    }

    from amr_twin.base.atomic_file import discard_after, place, temporary_name

    staged: list[
        tuple[Path, Path]
    ] = []  # (temporary of this process, recording) renamed at the end

    def target(kind: str, spec: RunSpec) -> str | None:
        if kind not in folders:
            return None
        final = folders[kind] / f"run{spec.number}.{kind}"
        staged.append((temporary_name(final), final))
        return str(staged[-1][0])

    todo = [
        RunJob(
            s,
            cfg,
            firmware,
            duration_s or s.duration_s,
            rrd_path=target("rrd", s),
            mcap_path=target("mcap", s),
        )
        for s in specs
    ]
    # §5.1.4's rolling-resistance study runs in the same pool, with the whole suite only
    study = (
        [
            (crr, RunJob(s, c, firmware, s.duration_s))
            for crr, c in payload.study_configs(cfg)
            for s in RUNS
            if s.number in payload.STUDY_RUNS
        ]
        if study and runs is None and duration_s is None
        else []
    )
    crr_of = {id(job): crr for crr, job in study}
    done, analysed = {}, []
    try:
        for job, raw in run_all(
            simulate, todo + [job for _, job in study], jobs, "chapter 5 runs", progress
        ):
            if id(job) in crr_of:
                analysed.append((crr_of[id(job)], analyse(job.spec, raw)))
            else:
                done[job.spec.number] = analyse(job.spec, raw)
    except BaseException:  # interrupted or failed: no recording of this call is left
        for tmp, _final in staged:
            discard_after(tmp)
        raise
    for tmp, final in staged:
        place(tmp, final)
    results = [done[s.number] for s in specs]
    out = {
        "firmware": firmware,
        "jobs": jobs,
        "sim_s": sum(r["duration_s"] for r in results),
        "runs": results,
        "study_runs": len(analysed),
        "study_sim_s": sum(a["duration_s"] for _, a in analysed),
        "comparisons": compare_oscillation(results),
        "crr": {"tyres": cfg.wheel.rolling_resistance, "balls": cfg.caster.rolling_resistance},
        "payload_duty": payload.duty_comparison(results),
        "rolling_resistance_study": payload.rolling_resistance_study(analysed) if study else [],
    }
    if reference_firmware is not None:
        from amr_twin.experiments.chapter5.firmware_comparison import PACE_US, compare
        from amr_twin.experiments.chapter5.pin_timeline import command_timeline, timeline_table

        ref = [
            RunJob(s, cfg, reference_firmware, duration_s or s.duration_s, extra=extra)
            for extra in ({}, {"pace_us": PACE_US})
            for s in specs
        ]
        ref_done = [
            analyse(job.spec, raw)
            for job, raw in run_all(
                simulate, ref, jobs, f"chapter 5 runs, {reference_firmware}", progress
            )
        ]
        out["firmware_comparison"] = compare(
            results,
            ref_done[: len(specs)],
            firmware,
            reference_firmware,
            paced=ref_done[len(specs) :],
        )
        if firmware.startswith("avr"):
            out["firmware_comparison"]["timeline"] = timeline_table(
                command_timeline(reference_firmware), command_timeline(firmware)
            )
    out["wall_s"] = time.perf_counter() - wall0
    return out


def plot(results: dict, out_dir: Path) -> list[Path]:
    """One PNG per run (``run<N>.png``), see :func:`.figure.plot`."""
    from amr_twin.experiments.chapter5.figure import plot as plot_runs

    return plot_runs(results, out_dir)


def report(results: dict, out_dir: Path) -> Chapter5Metrics:
    """Write ``metrics.json`` (from the typed metrics) and ``report.md`` (run :func:`plot` for the
    figures); return the metrics."""
    from amr_twin.experiments.chapter5.report import markdown
    from amr_twin.experiments.runner.executor import write_json, write_text

    data = metrics(results)
    written = data.as_json()
    write_json(Path(out_dir) / "metrics.json", written)
    write_text(Path(out_dir) / "report.md", markdown(written))
    return data
