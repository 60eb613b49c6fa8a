"""``amr-twin calibrate``: fit the twin's parameters to the thesis' bench point and chapter 5, or to
a logged run (CSV), and write the override file.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Optional

import typer

from amr_twin.cli.common import _config, _guard, fail
from amr_twin.cli.options import ConfigOpt, ParamsOpt, SetOpt


def calibrate(
    target: str = typer.Option(
        "thesis",
        help="'thesis' (bench point and chapter 5) or a CSV log with columns "
        "t_s, wheel, rpm, command.",
    ),
    out: Path = typer.Option(
        Path("params.yaml"), help="Override file to write (use it with --params)."
    ),
    report: Optional[Path] = typer.Option(
        None,
        "--report",
        help="Also write the calibration report: values, 1 "
        "sigma, correlations and how the fit follows the held parameters "
        "(what `--samples` draws from; models/amr/calibration.yaml).",
    ),
    no_fit: bool = typer.Option(
        False,
        "--no-fit",
        help="Do not fit: report the uncertainty of the given values "
        "(with --report; --out then holds them unchanged).",
    ),
    max_evaluations: int = typer.Option(
        90,
        help="Most twin evaluations of the fit, 7 to 2000 (a step costs one "
        "per fitted parameter and one more: the fit takes at most this // 6 steps).",
    ),
    jobs: Optional[int] = typer.Option(
        None,
        "--jobs",
        help="Worker processes for a thesis evaluation's three runs "
        "(default: the usable cores, at most 3; at most the usable cores).",
    ),
    as_json: bool = typer.Option(
        False,
        "--json",
        help="Print the result as one JSON object (values, sigma, "
        "correlations, features) instead of the summary.",
    ),
    config: Optional[Path] = ConfigOpt,
    params: Optional[Path] = ParamsOpt,
    set_: Optional[list[str]] = SetOpt,
) -> None:
    """Fit the drive's unknowns (driver gain, motor Ke and friction per wheel) with their
    uncertainty."""
    from rich.progress import Progress

    from amr_twin.calibration.fit import calibrate as fit_plant
    from amr_twin.calibration.fit import write_params
    from amr_twin.calibration.targets import read_log

    from amr_twin.recording.outputs import OutputError, check_file

    from amr_twin.calibration.fit import PARAMETERS, evaluations_per_step
    from amr_twin.base.process_pool import check_jobs

    if no_fit and report is None:
        fail("--no-fit needs --report FILE (without a fit, the report is the only result)")
    if not evaluations_per_step() <= max_evaluations <= MAX_EVALUATIONS:
        fail(
            f"--max-evaluations {max_evaluations}: must be in "
            f"{evaluations_per_step()}..{MAX_EVALUATIONS} (a fit "
            f"evaluates the starting point and once more per fitted parameter, "
            f"{len(PARAMETERS)}, for its Jacobian)"
        )
    try:
        jobs = min(check_jobs(jobs), 3) if jobs is None else check_jobs(jobs)
    except ValueError as exc:
        fail(str(exc))
    base = _config(config, params, set_)  # the starting point, with the user's overrides
    if target != "thesis":
        if not Path(target).exists():
            fail(f"--target {target!r}: neither 'thesis' nor an existing CSV file")
        try:  # a malformed log is refused before any simulation
            log = read_log(Path(target))
        except ValueError as exc:
            fail(f"--target {exc}")
        _guard(lambda: _check_log_comparable(base, log, target))
    try:
        check_file("--out", out)
        if report is not None:
            check_file("--report", report)
    except OutputError as exc:
        fail(str(exc))
    from rich.console import Console

    with Progress(transient=True, console=Console(stderr=True)) as bar:  # stdout: the result only
        fit = None
        if not no_fit:
            task = bar.add_task("calibrating", total=max_evaluations)
            fit = _guard(
                lambda: fit_plant(
                    target,
                    base=base,
                    max_evaluations=max_evaluations,
                    jobs=jobs,
                    progress=lambda i, n: bar.update(task, completed=min(i, n)),
                )
            )
        if report is not None:
            from amr_twin.calibration import report as calibration_report

            at = base if fit is None else _guard(lambda: fit.config(base))
            task = bar.add_task("uncertainty", total=1)
            result = _guard(
                lambda: calibration_report.evaluate(
                    at,
                    target,
                    jobs=jobs,
                    progress=lambda i, n: bar.update(task, total=n, completed=i),
                )
            )
            fit = result.as_fit(fit)  # the override file carries the report's uncertainty
    from amr_twin.base.atomic_file import all_or_nothing

    def write() -> None:
        with all_or_nothing():
            write_params(fit, out)
            if report is not None:
                calibration_report.write(result, report)

    _guard(write)
    if as_json:
        typer.echo(
            json.dumps(
                {**fit.report(), "out": str(out), **({"report": str(report)} if report else {})}
            )
        )
        return
    for line in fit.text_lines() + [
        "",
        f"wrote {out}" + (f" and the report {report}" if report else ""),
    ]:
        typer.echo(line)


MAX_EVALUATIONS = 2000
"""Most twin evaluations of one calibration (each simulates the thesis' three runs or the whole
log)."""


def _check_log_comparable(base, log: dict, target: str) -> None:
    """Refuse a log the twin cannot be compared with: it must publish two speeds per logged wheel.

    The fit compares the twin's published speeds with the log's over the log's span (plus
    ``LOG_TAIL_S``); a shorter log would only be scored by a fixed penalty, not fitted.
    """
    from amr_twin.calibration.targets import LOG_TAIL_S
    from amr_twin.assembly.twin import TwinOptions
    from amr_twin.assembly.command import Command
    from amr_twin.recording.run import run_command

    import logging

    logging.getLogger("amr_twin.controllers.wheel_command").addHandler(
        logging.NullHandler()
    )  # said below
    for text, wheels in log.items():
        refused = Command.parse(text).dry_run(base).last_error  # was blamed on the log's length
        if refused:
            raise ValueError(
                f"--target {target}: command {text}: the client refuses it ({refused})"
            )
        duration = max(float(v[:, 0].max()) for v in wheels.values()) + LOG_TAIL_S
        series = run_command(
            base, Command.parse(text), duration, TwinOptions(world="empty", visuals=False)
        ).series
        for w, samples in wheels.items():
            if len(series.published[w]) < 2:
                raise ValueError(
                    f"--target {target}: command {text}: in the log's {duration:g} s the twin "
                    f"publishes "
                    f"{len(series.published[w])} speed(s) of the {('left', 'right')[w]} wheel, 2 "
                    f"are "
                    "needed to compare: the log must be longer"
                )
