"""Checks of the experiment and sweep commands' options, each refusal one line (``fail``, exit 2).

Numbers and folders are checked before any model is built: the firmware and
``--jobs`` (:func:`amr_twin.base.process_pool.check_jobs`), recording
folders, every output (:mod:`amr_twin.recording.outputs`), the Dask scheduler. The experiments'
own rules (durations, runs, seeds, routes, sweep sizes) live in their specs
(``experiments/<name>/spec.py``)."""

from __future__ import annotations

from pathlib import Path
from typing import Optional

import typer

from amr_twin.cli.options import checked_firmware, checked_seed

JobsOpt = typer.Option(
    None, "--jobs", help="Worker processes (default: one per usable core; at most that)."
)
YesOpt = typer.Option(
    False,
    "--yes",
    help="Start without asking when the time estimated beforehand is above 10 min "
    "(without it such a run is refused, its estimate named).",
)

CPU_S_PER_SIM_S = {
    "sweep": 0.021,
    "chapter5": 0.045,
    "fusion": 0.16,
    "umbmark": 0.012,
    "navigation": 0.19,
}
"""CPU seconds per simulated second, as ``amr-twin bench --suites`` measured them (README's table):
a 100-point sweep of 8 s points took 15.7 to 16.7 s of CPU; chapter 5's 132 simulated s 5.4 to 5.8 s
on one job; the fusion experiment's 67 s drive, with its estimators, 9.8 to 10.4 s. The UMBmark
square (no sensors, the empty world): 0.73 s of CPU for its 60 simulated s (ten robots, 300
squares). Navigation (sensors, EKF + MPPI, the episodes' people and the SLAM map's build): 368 s of
CPU for the 32 runs of about 59 simulated s of ``experiment navigation --episodes 16 --seed 1``
(docs/explanation/navigation.md)."""
AVR_COST = 4.0
"""How much more the emulated ATmega2560 costs (the bench's avr_ratio, 5.5, against the loop's
1.3)."""
CONFIRM_ABOVE_S = 600.0
"""A run estimated to take longer than this (wall s) starts only with --yes."""


def _minutes(seconds: float) -> str:
    if seconds < 90:
        return f"{seconds:.0f} s"
    if seconds < 5400:
        return f"{seconds / 60:.1f} min"
    return f"{seconds / 3600:.1f} h"


def check_estimate(
    what: str, sim_s: float, kind: str, workers: int, firmware: str, yes: bool, fail
) -> float:
    """Estimate the wall time of ``sim_s`` simulated seconds on ``workers`` processes; above
    :data:`CONFIRM_ABOVE_S` refuse (one line naming the estimate and --yes) unless ``yes``; say it
    on stderr when above a minute. Returns the estimate, s."""
    cost = CPU_S_PER_SIM_S[kind] * (AVR_COST if firmware.startswith("avr") else 1.0)
    wall_s = sim_s * cost / max(1, workers)
    text = (
        f"{what}: about {_minutes(wall_s)} with {workers} worker{'s' if workers != 1 else ''} "
        f"({sim_s:.0f} simulated s at {cost:g} s of CPU each, as measured)"
    )
    if wall_s > CONFIRM_ABOVE_S and not yes:
        fail(
            f"{text}; above {CONFIRM_ABOVE_S / 60:.0f} min: add --yes to start it, or ask for less"
        )
    if wall_s > 60:
        typer.echo(f"note: {text}", err=True)
    return wall_s


def check_common(
    jobs: Optional[int], firmware: str, fail, sketch: Optional[Path] = None
) -> tuple[int, str]:
    """Firmware (and --sketch; an avr sketch is built now) and --jobs (None -> the usable cores).

    Returns the jobs to use and the firmware string (``avr:DIR`` with a sketch).
    """
    from amr_twin.base.process_pool import check_jobs

    kind = checked_firmware(firmware, sketch, fail)
    try:
        return check_jobs(jobs), kind
    except ValueError as exc:
        fail(str(exc))


def check_memory(
    duration_s: float,
    fail,
    recorded: bool = False,
    sensors: bool = False,
    processes: int = 1,
    what: str = "the run",
    rerun: bool = False,
) -> None:
    """Refuse (one line) runs whose estimated peak memory (:func:`amr_twin.sim.bounds.memory_mb`,
    one per process) exceeds what the machine has available now, or, with the Rerun recording
    (``rerun``), the address space it reserves, the process' limit (``ulimit -v``); nothing is
    refused where unknown."""
    from amr_twin.sim.bounds import (
        RERUN_ADDRESS_SPACE_MB,
        address_space_mb,
        available_mb,
        memory_mb,
    )

    limit = address_space_mb()
    space = memory_mb(duration_s, recorded, sensors) + (RERUN_ADDRESS_SPACE_MB if rerun else 0.0)
    if limit is not None and space > limit:
        fail(
            f"--duration-s {duration_s:g}{' with --record' if rerun else ''}: {what} would need "
            f"about "
            f"{space / 1024:.1f} GB of address "
            f"space{' (the Rerun recording reserves ~3 GB)' if rerun else ''}; "
            "the limit (ulimit -v) is "
            f"{limit / 1024:.1f} GB: raise it, or ask for less (a shorter run, no recording)"
        )
    need, have = memory_mb(duration_s, recorded, sensors) * processes, available_mb()
    if have is not None and need > have:
        kept = "its messages until they are written" if recorded else "its 100 Hz series"
        fail(
            f"--duration-s {duration_s:g}: {what} would need about {need / 1024:.1f} GB of "
            f"memory (it keeps {kept}"
            f"{f', {processes} processes' if processes > 1 else ''}); {have / 1024:.1f} GB are "
            f"available: "
            "ask for less (a shorter run, fewer --jobs, no recording)"
        )


def check_executor(executor: str, scheduler: Optional[str], fail) -> None:
    """``--executor local|dask``, ``--scheduler`` and the command's ``--scheduler-timeout-s`` (read
    from its context): dask needs an address, local takes neither (given with it, they were
    ignored)."""
    import math

    from amr_twin.cli.path_options import get_current_context
    from amr_twin.experiments.runner.executor import EXECUTORS

    if executor not in EXECUTORS:
        fail(f"--executor {executor!r}: must be one of {', '.join(EXECUTORS)}")
    if executor == "dask" and not scheduler:
        fail("--executor dask needs --scheduler ADDRESS (e.g. tcp://127.0.0.1:8786)")
    if executor == "local" and scheduler:
        fail("--scheduler is only used with --executor dask")
    ctx = get_current_context(silent=True)
    if ctx is None or "scheduler_timeout_s" not in ctx.params:
        return
    timeout_s, source = (
        ctx.params["scheduler_timeout_s"],
        ctx.get_parameter_source("scheduler_timeout_s"),
    )
    if executor == "local" and source is not None and source.name not in ("DEFAULT", "DEFAULT_MAP"):
        fail("--scheduler-timeout-s is only used with --executor dask")
    if not (math.isfinite(timeout_s) and 0 < timeout_s < 3600):
        fail(f"--scheduler-timeout-s {timeout_s:g}: must be in (0, 3600) s")


def check_record_folder(option: str, folder: Optional[Path], fail, name: str) -> None:
    """A recording option of a multi-run command takes a folder (one file per run), not a file
    name."""
    if folder is None or folder.is_dir():
        return
    if folder.exists():
        fail(
            f"{option} {folder}: exists and is not a folder (one {name} per run is written inside)"
        )
    if folder.suffix.lower() in (".rrd", ".mcap"):
        fail(
            f"{option} {folder}: give a folder, not a file name (one {name} per run is written "
            f"inside)"
        )


def check_outputs(fail, files: dict | None = None, folders: dict | None = None) -> None:
    """:func:`amr_twin.recording.outputs.check_outputs`, its refusal as one line and exit 2."""
    from amr_twin.recording.outputs import OutputError
    from amr_twin.recording.outputs import check_outputs as check

    try:
        check(files=files, folders=folders)
    except OutputError as exc:
        fail(str(exc))


def dask_client(scheduler: str, timeout_s: float, fail):
    """A connected ``distributed.Client``, or a one-line error and exit 2."""
    from amr_twin.experiments.runner.dask_cluster import ExecutorError, connect_dask

    try:
        return connect_dask(scheduler, timeout_s)
    except ExecutorError as exc:
        fail(str(exc))


SamplesOpt = typer.Option(
    1,
    "--samples",
    help="Runs per point with parameters drawn from their spreads (the "
    "ranges and sigmas in models/amr/README.md): medians, 90 % intervals and sensitivities. "
    "1: the nominal parameters only.",
)
SeedOpt = typer.Option(
    None,
    "--seed",
    help="Seed of the parameter draws with --samples (default 0; same seed, same draws).",
)
SamplerOpt = typer.Option(
    None,
    "--sampler",
    help="lhs (Latin hypercube, default) or sobol (N a power of 2), with --samples.",
)
CalibrationOpt = typer.Option(
    None,
    "--calibration",
    help="Calibration report the calibrated parameters are drawn "
    "from, with --samples (default: calibration.yaml beside the parameter file; "
    "amr-twin calibrate --report writes one).",
)


def parameter_draws(
    samples: int,
    seed: Optional[int],
    sampler: Optional[str],
    calibration: Optional[Path],
    config: Optional[Path],
    params: Optional[Path],
    sets: Optional[list[str]],
    fail,
):
    """``--samples`` and its options checked, and the drawn configurations (None for 1 sample).

    Everything is checked before any simulation: a draw the schema refuses names its
    sample and field.
    """
    from amr_twin.model.config import ConfigError
    from amr_twin.calibration.uncertainty import MAX_SAMPLES, SAMPLERS, ParameterSpace

    if not 1 <= samples <= MAX_SAMPLES:
        fail(f"--samples {samples}: must be in 1..{MAX_SAMPLES}")
    if samples == 1:
        given = [
            name
            for name, v in (
                ("--seed", seed),
                ("--sampler", sampler),
                ("--calibration", calibration),
            )
            if v is not None
        ]
        if given:
            fail(f"{', '.join(given)}: only used with --samples N (N >= 2)")
        return None
    checked_seed(seed, fail)
    if sampler is not None and sampler not in SAMPLERS:
        fail(f"--sampler {sampler!r}: must be one of {', '.join(SAMPLERS)}")
    if calibration is not None and not calibration.exists():
        fail(f"--calibration {calibration}: no such file (amr-twin calibrate --report writes one)")
    try:
        space = ParameterSpace.load(
            config, override_file=params, sets=sets or [], calibration=calibration
        )
        return space.draw(samples, seed=seed or 0, sampler=sampler or "lhs")
    except (ConfigError, ValueError) as exc:
        head, _, rest = str(exc).partition(":")
        fail(
            f"--calibration {calibration}:{rest}"
            if calibration is not None and head.endswith(str(calibration))
            else str(exc)
        )
