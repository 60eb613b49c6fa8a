"""``amr-twin experiment``: the thesis' experiments, each a command of this typer sub-app.

``chapter5`` and ``faults`` are defined here; ``fusion``, ``navigation`` and ``umbmark`` in their
own modules (:mod:`amr_twin.cli.fusion`, :mod:`amr_twin.cli.navigation`,
:mod:`amr_twin.cli.umbmark`) and added to :data:`app` below. Each simulates first and writes
afterwards, every file through a temporary file and a rename, the report and its plots together
(:func:`amr_twin.base.atomic_file.all_or_nothing`): a full disk leaves the previous report,
not half of a new one. Every output folder is checked before the first simulation
(:mod:`amr_twin.recording.outputs`).

``--record DIR`` / ``--mcap DIR`` take a folder: one recording per run (``run<N>.rrd``),
written by the worker that simulates it to a temporary name, renamed with the report at the end
(an interrupted run leaves none).
"""

from __future__ import annotations

from pathlib import Path
from typing import Optional

import typer

from amr_twin.cli.checks import (
    CalibrationOpt,
    JobsOpt,
    SamplerOpt,
    SamplesOpt,
    SeedOpt,
    YesOpt,
    check_common,
    check_estimate,
    check_memory,
    check_outputs,
    check_record_folder,
    parameter_draws,
)
from amr_twin.cli.common import _config, _guard, checked, fail
from amr_twin.cli.attainable import attainable
from amr_twin.cli.fusion import fusion
from amr_twin.cli.fleet_experiment import fleet_experiment
from amr_twin.cli.navigation import navigation
from amr_twin.cli.options import ConfigOpt, ParamsOpt, SetOpt, sketch_option
from amr_twin.cli.umbmark import umbmark


def _rpm(value) -> str:
    return "-" if value is None else f"{value:.2f}"


app = typer.Typer(no_args_is_help=True, help="Reproduce the thesis experiments.")
"""``amr-twin experiment``: chapter5 and faults (here), fusion, navigation and umbmark (their own
modules)."""


@app.command("chapter5")
def chapter5(
    out: Path = typer.Option(
        ..., "--out", help="Output folder: metrics.json, report.md, run<N>.png."
    ),
    jobs: Optional[int] = JobsOpt,
    firmware: str = typer.Option(
        "faithful",
        "--firmware",
        help="faithful, improved or avr; default faithful "
        "(firmware.md in docs/explanation/; with avr the runs are also done with faithful and the "
        "differences tabulated).",
    ),
    sketch: Optional[Path] = sketch_option(),
    runs: Optional[str] = typer.Option(
        None, "--runs", help="Run numbers to do, e.g. 1,3 (default all)."
    ),
    duration_s: Optional[float] = typer.Option(
        None, "--duration-s", help="Override every run's duration, s."
    ),
    record: Optional[Path] = typer.Option(
        None,
        "--record",
        metavar="DIR",
        help="Folder: one Rerun recording per run, DIR/run<N>.rrd (open with `rerun "
        "DIR/run1.rrd`).",
    ),
    mcap: Optional[Path] = typer.Option(
        None, "--mcap", metavar="DIR", help="Folder: one ROS 2 recording per run, DIR/run<N>.mcap."
    ),
    samples: int = SamplesOpt,
    seed: Optional[int] = SeedOpt,
    sampler: Optional[str] = SamplerOpt,
    calibration: Optional[Path] = CalibrationOpt,
    progress: bool = typer.Option(True, "--progress/--no-progress", help="Progress bar on stderr."),
    yes: bool = YesOpt,
    config: Optional[Path] = ConfigOpt,
    params: Optional[Path] = ParamsOpt,
    set_: Optional[list[str]] = SetOpt,
) -> None:
    """Run the eight step experiments of chapter 5 and judge them against the thesis; print wall
    time.

    With --samples N the runs are repeated with N parameter draws: each metric's median and
    90 % interval beside the thesis' value, and how many draws meet its band.
    """
    from amr_twin.experiments.chapter5.spec import Chapter5Spec, run

    jobs, firmware = check_common(jobs, firmware, fail, sketch)
    spec = Chapter5Spec(runs, duration_s, firmware)
    checked(spec.validate)
    check_record_folder("--record", record, fail, "run<N>.rrd")
    check_record_folder("--mcap", mcap, fail, "run<N>.mcap")
    check_memory(
        spec.longest_run_s(),
        fail,
        recorded=bool(record or mcap),
        processes=jobs,
        what="each run",
        rerun=record is not None,
    )
    check_outputs(fail, folders={"--out": out, "--record": record, "--mcap": mcap})
    cfg = _config(config, params, set_)
    draws = parameter_draws(samples, seed, sampler, calibration, config, params, set_, fail)
    passes = spec.passes(samples if draws is not None else 0)
    check_estimate(
        f"experiment chapter5: {passes} pass{'es' if passes != 1 else ''} of the runs",
        spec.pass_s() * passes,
        "chapter5",
        jobs,
        firmware,
        yes,
        fail,
    )

    def work():  # the recordings are renamed with the report, at the end: none if interrupted
        return run(
            spec,
            cfg,
            out,
            jobs=jobs,
            progress=progress,
            record_dir=record,
            mcap_dir=mcap,
            draws=draws,
        )

    data = _guard(work)
    from amr_twin.experiments.chapter5.findings import (
        ATTAINABLE_COMMAND,
        ATTAINABLE_SECTION,
        VALIDATION_DOC,
        VALIDATION_SECTION,
    )
    from amr_twin.experiments.chapter5.findings import lines as finding_lines
    from amr_twin.experiments.chapter5.report import passed_by_metric

    written = data.as_json()
    typer.echo(f"chapter 5 findings ({firmware} firmware; details in {out}/report.md):")
    for line in finding_lines(written["findings"]):
        typer.echo(f"  {line}")
    typer.echo(
        f'  why: {VALIDATION_DOC} (in the repository), section "{VALIDATION_SECTION}"; whether '
        f"any plant "
        f"inside the sourced ranges meets them: {ATTAINABLE_COMMAND}, section "
        f'"{ATTAINABLE_SECTION}"'
    )
    typer.echo(
        f"published checks passed by metric: {passed_by_metric(written, 'checks')}; oscillation "
        f"{data.oscillation_verdict['published_passed']} / "
        f"{data.oscillation_verdict['comparisons']}"
    )
    s = data.summary
    if data.firmware_comparison is not None:
        fc, w = data.firmware_comparison, data.firmware_comparison["worst"]
        typer.echo(
            f"{fc['firmware']} against {fc['reference']}, sample by sample: worst last-sample "
            f"difference "
            f"{_rpm(w['final_drpm'])} RPM, first sample {w['first_dt_ms']:.1f} ms apart: "
            f"{fc['verdict']}"
        )
    if data.spread is not None:
        sp = data.spread
        met = [m for m in sp["metrics"] if "thesis" in m]
        typer.echo(
            f"over {sp['samples']} parameter draws ({sp['wall_s']:.1f} s wall time): "
            f"{sum(m['in_band'] for m in met)} of {len(met) * sp['samples']} banded metrics in "
            f"their band "
            "(report.md, spread section)"
        )
        cp = sp["checks_passed"]
        typer.echo(
            f"checks passed over the draws: median {cp['published']['median']:.0f} "
            f"({cp['published']['low']:.0f}-{cp['published']['high']:.0f}) on the published "
            f"samples, "
            f"{cp['true']['median']:.0f} ({cp['true']['low']:.0f}-{cp['true']['high']:.0f}) on "
            f"the true speed"
        )
    typer.echo(
        f"all checks, attainable or not: {s.passed}/{s.checks} on the published samples (true "
        f"speed "
        f"{s.true_passed}/{s.true_checks}); wrote {out}/metrics.json, report.md"
    )
    study = f" and {data.study_runs} rolling-resistance study runs" if data.study_runs else ""
    typer.echo(
        f"wall time {data.wall_s:.2f} s for {len(data.runs)} runs{study}, "
        f"{data.sim_s + data.study_sim_s:.0f} simulated s (jobs {jobs}, firmware {firmware})"
    )
    for folder, ext in ((record, "rrd"), (mcap, "mcap")):
        if folder is not None:
            typer.echo(
                f"recordings: {folder}/run<N>.{ext} for runs "
                + ",".join(str(r.run) for r in data.runs)
            )


def faults_experiment(
    out: Path = typer.Option(
        ...,
        "--out",
        help="Output folder: faults.md, faults.json, img/faults_*.png (the committed page: "
        "faults.md in docs/reference/).",
    ),
    jobs: Optional[int] = JobsOpt,
    progress: bool = typer.Option(True, "--progress/--no-progress", help="Progress bar on stderr."),
    config: Optional[Path] = ConfigOpt,
    params: Optional[Path] = ParamsOpt,
    set_: Optional[list[str]] = SetOpt,
) -> None:
    """Inject each kind of fault under both firmwares and report what they do (faults.md in
    docs/reference/)."""
    from amr_twin.experiments.faults import experiment as faults, report as faults_report

    jobs, _ = check_common(jobs, "faithful", fail)
    check_outputs(fail, folders={"--out": out})
    cfg = _config(config, params, set_)

    def work():
        from amr_twin.base.atomic_file import all_or_nothing

        results = faults.run(cfg, jobs=jobs, progress=progress)
        with all_or_nothing():
            faults_report.plot(results, out)
            faults_report.report(results, out)
        return results

    results = _guard(work)
    for row in results["rows"]:
        left = row["wheels"]["left"]
        typer.echo(
            f"{row['fault']:28s} {row['firmware']:9s} left {left['true_during_rpm']:6.1f} RPM, "
            f"offset {row['end_offset_m']:5.2f} m / {row['end_heading_offset_deg']:5.0f} deg, "
            f"stopped {'yes' if row['stopped_at_end'] else 'NO'}"
        )
    typer.echo(
        f"wall time {results['wall_s']:.1f} s; wrote {out}/faults.md, faults.json, img/faults_*.png"
    )


app.command("fusion")(fusion)
app.command("fleet")(fleet_experiment)
app.command("navigation")(navigation)
app.command("umbmark")(umbmark)
app.command("faults")(faults_experiment)
app.command("chapter5-attainable")(attainable)
