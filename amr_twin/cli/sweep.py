"""``amr-twin sweep``: parameter sweeps over many simulations (a typer sub-app); ``payload`` so far.

The sweep simulates first and writes afterwards, every file through a temporary file and a
rename: an interrupted sweep keeps the per-point files already finished (``runs/<key>.json``),
and a rerun only simulates the missing ones. The report and its plots are written together
(:func:`amr_twin.base.atomic_file.all_or_nothing`). Every output folder is checked before
the first simulation (:mod:`amr_twin.recording.outputs`). ``--record DIR`` / ``--mcap DIR``: one
recording per point simulated (``<key>.rrd``), written by the worker that simulates it; a resumed
sweep records only the points it simulates.
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
    check_executor,
    check_memory,
    check_outputs,
    check_record_folder,
    dask_client,
    parameter_draws,
)
from amr_twin.cli.common import _config, _guard, checked, fail
from amr_twin.cli.options import ConfigOpt, ParamsOpt, SetOpt, firmware_option, sketch_option

app = typer.Typer(no_args_is_help=True, help="Parameter sweeps over many simulations.")
"""``amr-twin sweep``: payload."""


def _safe_interval(results: dict, position: str) -> str:
    """``; over N draws: median M kg (90 %: L - H)`` of a sweep with samples, else ''."""
    answer = results.get("answers", {}).get(position, {}).get("highest_safe_kg")
    if not answer or not answer["n"]:
        return ""
    kg = {float("-inf"): "none"}
    return (
        f"; over {answer['n']} draws: median {kg.get(answer['median'], answer['median'])} kg "
        f"(90 %: {kg.get(answer['low'], answer['low'])} - {kg.get(answer['high'], answer['high'])})"
    )


@app.command("payload")
def payload(
    out: Path = typer.Option(
        ..., "--out", help="Output folder: runs/, sweep.csv, summary.md/json, PNGs."
    ),
    masses: str = typer.Option("0:60:5", "--masses", help="START:STOP:STEP or M1,M2,... kg."),
    positions: str = typer.Option(
        "center,front,rear,left,right",
        "--positions",
        help="Named positions (box flush with the deck edges) or X:Y in metres.",
    ),
    commands: str = typer.Option(
        "linear:0.7,angular:60:-1",
        "--commands",
        help="linear:V, angular:DEG_S:ICC_M, motor:left|right:V (comma separated).",
    ),
    duration_s: float = typer.Option(
        8.0, "--duration-s", help="Simulated seconds per point (at most 3600)."
    ),
    jobs: Optional[int] = JobsOpt,
    firmware: str = firmware_option(),
    sketch: Optional[Path] = sketch_option(),
    executor: str = typer.Option(
        "local", "--executor", help="local (process pool of --jobs) or dask."
    ),
    scheduler: Optional[str] = typer.Option(
        None, "--scheduler", help="Dask scheduler address, e.g. tcp://127.0.0.1:8786."
    ),
    scheduler_timeout_s: float = typer.Option(
        5.0, "--scheduler-timeout-s", help="Give up reaching the Dask scheduler after this long, s."
    ),
    record: Optional[Path] = typer.Option(
        None,
        "--record",
        metavar="DIR",
        help="Folder: one Rerun recording per point simulated now, DIR/<key>.rrd (key as in "
        "runs/<key>.json). "
        "A resumed sweep does not redo finished points to record them: delete runs/<key>.json "
        "for that. "
        "With --executor dask the workers write it: DIR must be on shared storage.",
    ),
    mcap: Optional[Path] = typer.Option(
        None,
        "--mcap",
        metavar="DIR",
        help="Folder: one ROS 2 recording per point simulated now, DIR/<key>.mcap.",
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
    """Sweep payload mass x position x command; resume by skipping the points already done.

    With --samples N each point also runs N times with parameters drawn from their spreads:
    every metric as median and 90 % interval, the highest safe payload per position as an
    interval, and the parameters that move each answer (summary.md, sensitivity.csv).
    """
    from amr_twin.experiments.payload import (
        sweep as payload_sweep,
        sweep_report as payload_sweep_report,
    )
    from amr_twin.experiments.payload.spec import PayloadSweepSpec

    jobs, firmware = check_common(jobs, firmware, fail, sketch)
    check_executor(executor, scheduler, fail)
    spec = PayloadSweepSpec(masses, positions, commands, duration_s, samples)
    checked(spec.check_duration)
    cfg = _config(config, params, set_)
    grid = checked(spec.grid, cfg)
    if grid.repeated:
        typer.echo(
            "note: repeated sweep values are simulated once: "
            + ", ".join(str(v) for v in grid.repeated),
            err=True,
        )
    checked(spec.check_size, grid)
    n_points, runs = grid.points, spec.runs(grid)
    draws = parameter_draws(samples, seed, sampler, calibration, config, params, set_, fail)
    check_record_folder("--record", record, fail, "<key>.rrd")
    check_record_folder("--mcap", mcap, fail, "<key>.mcap")
    check_memory(
        duration_s,
        fail,
        recorded=bool(record or mcap),
        processes=jobs if executor == "local" else 1,
        what="each point",
    )
    check_outputs(fail, folders={"--out": out, "--record": record, "--mcap": mcap})

    client = dask_client(scheduler, scheduler_timeout_s, fail) if executor == "dask" else None
    workers = jobs if client is None else max(1, sum(client.nthreads().values()))

    def estimate(todo: int) -> None:  # the points not done yet, before the first is simulated
        check_estimate(
            f"sweep payload: {todo} points to simulate (of {runs})",
            todo * duration_s,
            "sweep",
            workers,
            firmware,
            yes,
            fail,
        )

    def work():
        from amr_twin.base.atomic_file import all_or_nothing

        results = payload_sweep.run(
            cfg,
            out,
            grid.masses,
            grid.positions,
            grid.commands,
            duration_s=duration_s,
            jobs=jobs,
            firmware=firmware,
            progress=progress,
            client=client,
            record_dir=record,
            mcap_dir=mcap,
            draws=draws,
            before=estimate,
        )
        if draws is not None:
            from amr_twin.experiments.payload import spread_report

            spread_report.analyse(results)
            with all_or_nothing():
                spread_report.plot(results, out)
                return results, spread_report.report(results, out)["positions"]
        improved = payload_sweep.improved_beside(
            cfg, out, results, jobs=jobs, progress=progress, client=client
        )
        with all_or_nothing():
            payload_sweep_report.plot(results, out, improved)
            return results, payload_sweep_report.report(results, out, improved)

    try:
        results, summary = _guard(work)
    finally:
        if client is not None:
            client.close()
    lines = (
        payload_sweep_report.answer_lines(summary, results)
        if draws is None
        else [
            f"{position:20s} {s['answer']}{_safe_interval(results, position)}"
            for position, s in summary.items()
        ]
    )
    for line in lines:
        typer.echo(line)
    where = f"dask {scheduler}" if client is not None else f"jobs {jobs}"
    what = "points" if draws is None else f"runs ({n_points} points x {samples} draws + nominal)"
    typer.echo(
        f"{len(results['rows'])} {what}: {results['simulated']} simulated, {results['reused']} "
        f"reused; "
        f"wall time {results['wall_s']:.2f} s ({where}); wrote {out}/sweep.csv, summary.md"
        + (", intervals.csv, sensitivity.csv" if draws is not None else "")
    )
    if record is not None or mcap is not None:
        typer.echo(
            f"recordings: {results['recorded']} points recorded in "
            + ", ".join(str(f) for f in (record, mcap) if f is not None)
            + (
                f"; {results['reused']} points reused from {out}/runs are not re-simulated to be "
                f"recorded "
                "(delete runs/<key>.json to record one)"
                if results["reused"]
                else ""
            )
        )
