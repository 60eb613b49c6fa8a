"""``amr-twin experiment chapter5`` and ``amr-twin sweep payload`` (typer sub-apps).

Both simulate first and write afterwards, every file through a temporary file and a
rename: an interrupted command leaves no half-written output (the sweep keeps the
per-point files already finished, and a rerun only simulates the missing ones). The
report and its plots are written together (:func:`amr_twin.recording.atomic_file.all_or_nothing`):
a full disk leaves the previous report, not half of a new one. Every output folder is
checked before the first simulation (:mod:`amr_twin.recording.outputs`).

``--record DIR`` / ``--mcap DIR`` take a folder: one recording per run
(``run<N>.rrd``) or per sweep point (``<key>.rrd``), written by the worker that
simulates it. A resumed sweep records only the points it simulates.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Optional

import typer

from amr_twin.cli.checks import (MAX_SWEEP_POINTS, CalibrationOpt, JobsOpt, SamplerOpt, SamplesOpt, SeedOpt, YesOpt,
                                 check_common, check_duration, check_estimate, check_executor, check_memory,
                                 check_outputs, check_record_folder, dask_client, parameter_draws, unique)
from amr_twin.cli.options import firmware_option, sketch_option

def _rpm(value) -> str:
    return "-" if value is None else f"{value:.2f}"


def _safe_interval(results: dict, position: str) -> str:
    """``; over N draws: median M kg (90 %: L - H)`` of a sweep with samples, else ''."""
    answer = results.get("answers", {}).get(position, {}).get("highest_safe_kg")
    if not answer or not answer["n"]:
        return ""
    kg = {float("-inf"): "none"}
    return (f"; over {answer['n']} draws: median {kg.get(answer['median'], answer['median'])} kg "
            f"(90 %: {kg.get(answer['low'], answer['low'])} - {kg.get(answer['high'], answer['high'])})")


def register(app: typer.Typer) -> None:
    """Add the ``experiment`` and ``sweep`` command groups to ``app``.

    Each command is added by its own ``_add_<name>(group)`` function; a new
    experiment adds one such function and one call here.
    """
    experiment = typer.Typer(no_args_is_help=True, help="Reproduce the thesis experiments.")
    sweep = typer.Typer(no_args_is_help=True, help="Parameter sweeps over many simulations.")
    app.add_typer(experiment, name="experiment")
    app.add_typer(sweep, name="sweep")
    _add_chapter5(experiment)
    from amr_twin.cli.fusion import add_fusion

    add_fusion(experiment)
    from amr_twin.cli.navigation import add_navigation

    add_navigation(experiment)
    from amr_twin.cli.umbmark import add_umbmark

    add_umbmark(experiment)
    _add_faults(experiment)
    _add_payload_sweep(sweep)


def _add_faults(experiment: typer.Typer) -> None:
    """``amr-twin experiment faults``."""
    from amr_twin.cli.common import _config, _guard, fail
    from amr_twin.cli.options import ConfigOpt, ParamsOpt, SetOpt

    @experiment.command("faults")
    def faults_cmd(
        out: Path = typer.Option(..., "--out", help="Output folder: faults.md, faults.json, img/faults_*.png "
                                 "(--out docs regenerates docs/faults.md)."),
        jobs: Optional[int] = JobsOpt,
        progress: bool = typer.Option(True, "--progress/--no-progress", help="Progress bar on stderr."),
        config: Optional[Path] = ConfigOpt, params: Optional[Path] = ParamsOpt, set_: Optional[list[str]] = SetOpt,
    ) -> None:
        """Inject each kind of fault under both firmwares and report what they do (docs/faults.md)."""
        from amr_twin.experiments import faults, faults_report

        jobs, _ = check_common(jobs, "faithful", fail)
        check_outputs(fail, folders={"--out": out})
        cfg = _config(config, params, set_)

        def work():
            from amr_twin.recording.atomic_file import all_or_nothing

            results = faults.run(cfg, jobs=jobs, progress=progress)
            with all_or_nothing():
                faults_report.plot(results, out)
                faults_report.report(results, out)
            return results

        results = _guard(work)
        for row in results["rows"]:
            left = row["wheels"]["left"]
            typer.echo(f"{row['fault']:28s} {row['firmware']:9s} left {left['true_during_rpm']:6.1f} RPM, "
                       f"offset {row['end_offset_m']:5.2f} m / {row['end_heading_offset_deg']:5.0f} deg, "
                       f"stopped {'yes' if row['stopped_at_end'] else 'NO'}")
        typer.echo(f"wall time {results['wall_s']:.1f} s; wrote {out}/faults.md, faults.json, img/faults_*.png")


def _add_chapter5(experiment: typer.Typer) -> None:
    """``amr-twin experiment chapter5``."""
    from amr_twin.cli.common import _config, _guard, fail
    from amr_twin.cli.options import ConfigOpt, ParamsOpt, SetOpt

    @experiment.command("chapter5")
    def chapter5_cmd(
        out: Path = typer.Option(..., "--out", help="Output folder: metrics.json, report.md, run<N>.png."),
        jobs: Optional[int] = JobsOpt,
        firmware: str = typer.Option("faithful", "--firmware", help="faithful, improved or avr; default faithful "
                                     "(docs/firmware.md; with avr the runs are also done with faithful and the "
                                     "differences tabulated)."),
        sketch: Optional[Path] = sketch_option(),
        runs: Optional[str] = typer.Option(None, "--runs", help="Run numbers to do, e.g. 1,3 (default all)."),
        duration_s: Optional[float] = typer.Option(None, "--duration-s", help="Override every run's duration, s."),
        record: Optional[Path] = typer.Option(
            None, "--record", metavar="DIR",
            help="Folder: one Rerun recording per run, DIR/run<N>.rrd (open with `rerun DIR/run1.rrd`)."),
        mcap: Optional[Path] = typer.Option(
            None, "--mcap", metavar="DIR", help="Folder: one ROS 2 recording per run, DIR/run<N>.mcap."),
        samples: int = SamplesOpt, seed: Optional[int] = SeedOpt, sampler: Optional[str] = SamplerOpt,
        calibration: Optional[Path] = CalibrationOpt,
        progress: bool = typer.Option(True, "--progress/--no-progress", help="Progress bar on stderr."),
        yes: bool = YesOpt,
        config: Optional[Path] = ConfigOpt, params: Optional[Path] = ParamsOpt, set_: Optional[list[str]] = SetOpt,
    ) -> None:
        """Run the eight step experiments of chapter 5 and judge them against the thesis; print wall time.

        With --samples N the runs are repeated with N parameter draws: each metric's median and
        90 % interval beside the thesis' value, and how many draws meet its band.
        """
        from amr_twin.experiments import chapter5

        jobs, firmware = check_common(jobs, firmware, fail, sketch)
        check_duration(duration_s, fail)
        try:
            numbers = None if runs is None else [int(v) for v in runs.split(",")]
        except ValueError:
            fail(f"--runs {runs!r}: expected run numbers 1..8 separated by commas")
        if numbers is not None and not all(1 <= n <= len(chapter5.RUNS) for n in numbers):
            fail(f"--runs {runs!r}: run numbers must lie in 1..{len(chapter5.RUNS)}")
        if numbers is not None and len(set(numbers)) != len(numbers):  # run once, silently
            fail(f"--runs {runs!r}: a run is named twice")
        check_record_folder("--record", record, fail, "run<N>.rrd")
        check_record_folder("--mcap", mcap, fail, "run<N>.mcap")
        check_memory(duration_s or max(r.duration_s for r in chapter5.RUNS), fail, recorded=bool(record or mcap),
                     processes=jobs, what="each run", rerun=record is not None)
        check_outputs(fail, folders={"--out": out, "--record": record, "--mcap": mcap})
        cfg = _config(config, params, set_)
        draws = parameter_draws(samples, seed, sampler, calibration, config, params, set_, fail)
        one_pass_s = sum(duration_s or r.duration_s for r in chapter5.RUNS if numbers is None or r.number in numbers)
        passes = 1 + (samples if draws is not None else 0) + (2 if firmware.startswith("avr") else 0) \
            + (1 if numbers is None and duration_s is None else 0)  # the rolling-resistance study: at most a pass
        check_estimate(f"experiment chapter5: {passes} pass{'es' if passes != 1 else ''} of the runs",
                       one_pass_s * passes, "chapter5", jobs, firmware, yes, fail)

        def work():
            from amr_twin.recording.atomic_file import all_or_nothing

            results = chapter5.run(cfg, jobs=jobs, firmware=firmware, runs=numbers, duration_s=duration_s,
                                   progress=progress, record_dir=record, mcap_dir=mcap,
                                   reference_firmware="faithful" if firmware.startswith("avr") else None)
            if draws is not None:
                from amr_twin.experiments import chapter5_spread

                results["spread"] = chapter5_spread.run(cfg, draws, jobs=jobs, firmware=firmware, runs=numbers,
                                                        duration_s=duration_s, progress=progress)
                results["spread_summary"] = chapter5_spread.summarise(results, results["spread"])
            with all_or_nothing():
                chapter5.plot(results, out)
                return chapter5.report(results, out)

        data = _guard(work)
        for r in data["runs"]:
            for wheel, w in r["wheels"].items():
                verdicts = " ".join(f"{k}={'ok' if c['verdict'] == 'pass' else 'MISS'}" for k, c in w["checks"].items())
                typer.echo(f"run {r['run']} {wheel:5s} {w['reference_rpm']:8.2f} RPM  {verdicts}")
        for c in data["comparisons"]:
            typer.echo(f"run {c['loaded_run']} (20 kg) against run {c['unloaded_run']} {c['wheel']:5s} "
                       f"{c['measure']} {_rpm(c['loaded'])} / {_rpm(c['unloaded'])} RPM: {c['verdict']} "
                       f"(true speed {_rpm(c['true_loaded'])} / {_rpm(c['true_unloaded'])}: {c['true_verdict']})")
        s = data["summary"]
        if "firmware_comparison" in data:
            fc, w = data["firmware_comparison"], data["firmware_comparison"]["worst"]
            typer.echo(f"{fc['firmware']} against {fc['reference']}, sample by sample: worst last-sample difference "
                       f"{_rpm(w['final_drpm'])} RPM, first sample {w['first_dt_ms']:.1f} ms apart: {fc['verdict']}")
        if "spread" in data:
            sp = data["spread"]
            met = [m for m in sp["metrics"] if "thesis" in m]
            typer.echo(f"over {sp['samples']} parameter draws ({sp['wall_s']:.1f} s wall time): "
                       f"{sum(m['in_band'] for m in met)} of {len(met) * sp['samples']} banded metrics in their band "
                       "(report.md, spread section)")
        typer.echo(f"checks passed {s['passed']}/{s['checks']} on the published samples (true speed "
                   f"{s['true_passed']}/{s['true_checks']}); wrote {out}/metrics.json, report.md")
        study = f" and {data['study_runs']} rolling-resistance study runs" if data["study_runs"] else ""
        typer.echo(f"wall time {data['wall_s']:.2f} s for {len(data['runs'])} runs{study}, "
                   f"{data['sim_s'] + data['study_sim_s']:.0f} simulated s (jobs {jobs}, firmware {firmware})")
        for folder, ext in ((record, "rrd"), (mcap, "mcap")):
            if folder is not None:
                typer.echo(f"recordings: {folder}/run<N>.{ext} for runs "
                           + ",".join(str(r["run"]) for r in data["runs"]))


def _add_payload_sweep(sweep: typer.Typer) -> None:
    """``amr-twin sweep payload``."""
    from amr_twin.cli.common import _config, _guard, fail
    from amr_twin.cli.options import ConfigOpt, ParamsOpt, SetOpt

    @sweep.command("payload")
    def payload_cmd(
        out: Path = typer.Option(..., "--out", help="Output folder: runs/, sweep.csv, summary.md/json, PNGs."),
        masses: str = typer.Option("0:60:5", "--masses", help="START:STOP:STEP or M1,M2,... kg."),
        positions: str = typer.Option("center,front,rear,left,right", "--positions",
                                      help="Named positions (box flush with the deck edges) or X:Y in metres."),
        commands: str = typer.Option("linear:0.7,angular:60:-1", "--commands",
                                     help="linear:V, angular:DEG_S:ICC_M, motor:left|right:V (comma separated)."),
        duration_s: float = typer.Option(8.0, "--duration-s", help="Simulated seconds per point (at most 3600)."),
        jobs: Optional[int] = JobsOpt,
        firmware: str = firmware_option(),
        sketch: Optional[Path] = sketch_option(),
        executor: str = typer.Option("local", "--executor", help="local (process pool of --jobs) or dask."),
        scheduler: Optional[str] = typer.Option(None, "--scheduler",
                                                help="Dask scheduler address, e.g. tcp://127.0.0.1:8786."),
        scheduler_timeout_s: float = typer.Option(5.0, "--scheduler-timeout-s",
                                                  help="Give up reaching the Dask scheduler after this long, s."),
        record: Optional[Path] = typer.Option(
            None, "--record", metavar="DIR",
            help="Folder: one Rerun recording per point simulated now, DIR/<key>.rrd (key as in runs/<key>.json). "
                 "A resumed sweep does not redo finished points to record them: delete runs/<key>.json for that. "
                 "With --executor dask the workers write it: DIR must be on shared storage."),
        mcap: Optional[Path] = typer.Option(
            None, "--mcap", metavar="DIR",
            help="Folder: one ROS 2 recording per point simulated now, DIR/<key>.mcap."),
        samples: int = SamplesOpt, seed: Optional[int] = SeedOpt, sampler: Optional[str] = SamplerOpt,
        calibration: Optional[Path] = CalibrationOpt,
        progress: bool = typer.Option(True, "--progress/--no-progress", help="Progress bar on stderr."),
        yes: bool = YesOpt,
        config: Optional[Path] = ConfigOpt, params: Optional[Path] = ParamsOpt, set_: Optional[list[str]] = SetOpt,
    ) -> None:
        """Sweep payload mass x position x command; resume by skipping the points already done.

        With --samples N each point also runs N times with parameters drawn from their spreads:
        every metric as median and 90 % interval, the highest safe payload per position as an
        interval, and the parameters that move each answer (summary.md, sensitivity.csv).
        """
        from amr_twin.experiments import payload_point, payload_sweep, payload_sweep_report

        jobs, firmware = check_common(jobs, firmware, fail, sketch)
        check_executor(executor, scheduler, fail)
        if not math.isfinite(duration_s):
            fail(f"--duration-s {duration_s}: must be a finite number")
        check_duration(duration_s, fail)
        cfg = _config(config, params, set_)
        try:
            mass_list = payload_point.parse_masses(masses)
            payload_point.check_masses(masses, mass_list)
            position_list = [p.strip() for p in positions.split(",") if p.strip()]
            for p in position_list:
                payload_point.check_on_deck(cfg, p)
            command_list = [c.strip() for c in commands.split(",") if c.strip()]
            for c in command_list:
                payload_point.check_accepted(cfg, c)
        except ValueError as exc:
            fail(str(exc))
        if not position_list or not command_list:
            fail("--positions and --commands must name at least one item each")
        mass_list, dup_m = unique(mass_list, float)
        position_list, dup_p = unique(position_list, lambda p: payload_point.position_xy_m(cfg, p))
        command_list, dup_c = unique(command_list, payload_point.parse_command)
        if dup_m or dup_p or dup_c:
            typer.echo("note: repeated sweep values are simulated once: "
                       + ", ".join(str(v) for v in dup_m + dup_p + dup_c), err=True)
        n_points = len(mass_list) * len(position_list) * len(command_list)
        runs = n_points * (1 + samples if samples > 1 else 1)
        if runs > MAX_SWEEP_POINTS:
            what = f" x (--samples + 1): {runs} runs" if samples > 1 else f": {n_points} points"
            fail(f"--masses x --positions x --commands{what}; at most {MAX_SWEEP_POINTS} per sweep "
                 f"(each is a simulation of {duration_s:g} s and a file in runs/): split the sweep")
        draws = parameter_draws(samples, seed, sampler, calibration, config, params, set_, fail)
        check_record_folder("--record", record, fail, "<key>.rrd")
        check_record_folder("--mcap", mcap, fail, "<key>.mcap")
        check_memory(duration_s, fail, recorded=bool(record or mcap), processes=jobs if executor == "local" else 1,
                     what="each point")
        check_outputs(fail, folders={"--out": out, "--record": record, "--mcap": mcap})

        client = dask_client(scheduler, scheduler_timeout_s, fail) if executor == "dask" else None
        workers = jobs if client is None else max(1, sum(client.nthreads().values()))

        def estimate(todo: int) -> None:  # the points not done yet, before the first is simulated
            check_estimate(f"sweep payload: {todo} points to simulate (of {runs})", todo * duration_s, "sweep",
                           workers, firmware, yes, fail)

        def work():
            from amr_twin.recording.atomic_file import all_or_nothing

            results = payload_sweep.run(cfg, out, mass_list, position_list, command_list, duration_s=duration_s,
                                        jobs=jobs, firmware=firmware, progress=progress, client=client,
                                        record_dir=record, mcap_dir=mcap, draws=draws, before=estimate)
            if draws is not None:
                from amr_twin.experiments import payload_spread_report as spread_report

                spread_report.analyse(results)
                with all_or_nothing():
                    spread_report.plot(results, out)
                    return results, spread_report.report(results, out)["positions"]
            improved = payload_sweep.improved_beside(cfg, out, results, jobs=jobs, progress=progress, client=client)
            with all_or_nothing():
                payload_sweep_report.plot(results, out, improved)
                return results, payload_sweep_report.report(results, out, improved)

        try:
            results, summary = _guard(work)
        finally:
            if client is not None:
                client.close()
        lines = (payload_sweep_report.answer_lines(summary, results) if draws is None else
                 [f"{position:20s} {s['answer']}{_safe_interval(results, position)}" for position, s in summary.items()])
        for line in lines:
            typer.echo(line)
        where = f"dask {scheduler}" if client is not None else f"jobs {jobs}"
        what = "points" if draws is None else f"runs ({n_points} points x {samples} draws + nominal)"
        typer.echo(f"{len(results['rows'])} {what}: {results['simulated']} simulated, {results['reused']} reused; "
                   f"wall time {results['wall_s']:.2f} s ({where}); wrote {out}/sweep.csv, summary.md"
                   + (", intervals.csv, sensitivity.csv" if draws is not None else ""))
        if record is not None or mcap is not None:
            typer.echo(f"recordings: {results['recorded']} points recorded in "
                       + ", ".join(str(f) for f in (record, mcap) if f is not None)
                       + (f"; {results['reused']} points reused from {out}/runs are not re-simulated to be recorded "
                          "(delete runs/<key>.json to record one)" if results["reused"] else ""))
