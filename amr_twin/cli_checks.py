"""Checks of the experiment and sweep commands' options, each refusal one line (``fail``, exit 2).

Numbers and folders are checked before any model is built: the firmware and
``--jobs`` (:func:`amr_twin.experiments.executor.check_jobs`), durations, recording
folders, every output (:mod:`amr_twin.outputs`), repeated sweep values, the Dask
scheduler.
"""

from __future__ import annotations

from pathlib import Path
from typing import Optional

import typer

from .cli_options import checked_firmware

MAX_DURATION_S = 3600.0
"""Longest simulated run of an experiment, s (see amr_twin.cli_run.MAX_RUN_S)."""

MAX_SWEEP_POINTS = 10_000
"""Most points of one sweep: each is a simulation (~0.5 s of CPU for 8 s) and a file in runs/."""

JobsOpt = typer.Option(None, "--jobs", help="Worker processes (default: one per usable core; at most that).")


def check_common(jobs: Optional[int], firmware: str, fail, sketch: Optional[Path] = None) -> tuple[int, str]:
    """Firmware (and --sketch; an avr sketch is built now) and --jobs (None -> the usable cores).

    Returns the jobs to use and the firmware string (``avr:DIR`` with a sketch).
    """
    from .experiments.executor import check_jobs

    kind = checked_firmware(firmware, sketch, fail)
    try:
        return check_jobs(jobs), kind
    except ValueError as exc:
        fail(str(exc))


def check_duration(duration_s: Optional[float], fail) -> None:
    if duration_s is not None and not (0 < duration_s <= MAX_DURATION_S):
        fail(f"--duration-s {duration_s:g}: must be in (0, {MAX_DURATION_S:g}] s (each run keeps its 100 Hz "
             "series in memory)")


def check_record_folder(option: str, folder: Optional[Path], fail, name: str) -> None:
    """A recording option of a multi-run command takes a folder (one file per run), not a file name."""
    if folder is None or folder.is_dir():
        return
    if folder.exists():
        fail(f"{option} {folder}: exists and is not a folder (one {name} per run is written inside)")
    if folder.suffix.lower() in (".rrd", ".mcap"):
        fail(f"{option} {folder}: give a folder, not a file name (one {name} per run is written inside)")


def check_outputs(fail, files: dict | None = None, folders: dict | None = None) -> None:
    """:func:`amr_twin.outputs.check_outputs`, its refusal as one line and exit 2."""
    from .outputs import OutputError
    from .outputs import check_outputs as check

    try:
        check(files=files, folders=folders)
    except OutputError as exc:
        fail(str(exc))


def unique(items: list, key) -> tuple[list, list]:
    """``items`` without repeats (by ``key``), in order; and the repeats dropped."""
    seen, kept, dropped = set(), [], []
    for item in items:
        k = key(item)
        (dropped if k in seen else kept).append(item)
        seen.add(k)
    return kept, dropped


def dask_client(scheduler: str, timeout_s: float, fail):
    """A connected ``distributed.Client``, or a one-line error and exit 2."""
    from .experiments.executor import ExecutorError, connect_dask

    try:
        return connect_dask(scheduler, timeout_s)
    except ExecutorError as exc:
        fail(str(exc))
