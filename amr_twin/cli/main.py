"""The ``amr-twin`` command line (typer).

Every command takes the parameter file, an override YAML and ``--set key=value``.
Bad input ends with one line on stderr naming the field (or the file, or the
option) and what is allowed, exit code 2, checked before the work starts, and no
output file written; a usage error of the parser (an unknown option, a value that
is not a number) is one line too. A file that cannot be written at the end (a full
disk) is one line and exit code 1, with none of the command's files left half-made.
"""

from __future__ import annotations

import contextlib
import gc
import json
import logging
import math
import os
import sys
from pathlib import Path
from typing import Optional

# Set before anything imports numpy, MuJoCo or pydantic (the values a user exported win):
# headless: MuJoCo need not load its OpenGL bindings (glfw, ~0.1 s of start-up) unless asked to
os.environ.setdefault("MUJOCO_GL", "disable")
# no pydantic plugins in the command line's process (its entry-point scan is ~12 ms of every
# start-up); PYDANTIC_DISABLE_PLUGINS= (empty) in the environment brings them back
os.environ.setdefault("PYDANTIC_DISABLE_PLUGINS", "__all__")
# numpy's OpenBLAS on one thread: its worker threads spin-wait after start-up and after each call
# (~0.11 s of CPU on `import numpy` on 2 cores, a sixth of a 1 s run), while the twin's matrices are
# small (a 14 x 14 mass matrix, 3 x 3 covariances); the pool workers inherit it (on 2 cores they
# competed)
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
# matplotlib's own warnings are not the command's: one that cannot save its font cache (a full disk,
# a file-size limit) would print a second line beside the command's one-line error, and the cache is
# only a speed-up (it is rebuilt at the next start); a real failure to draw still raises and is
# reported
logging.getLogger("matplotlib").setLevel(logging.ERROR)

import typer  # noqa: E402

try:  # typer >= 0.20 carries its own copy of click
    from typer._click import exceptions as _click_errors
except ImportError:  # pragma: no cover - older typer on click
    from click import exceptions as _click_errors

from amr_twin.cli import experiment as experiment_group
from amr_twin.cli import run as run_group
from amr_twin.cli import sweep as sweep_group
from amr_twin.cli.common import _config, _guard, fail, start_up
from amr_twin.cli.fleet import fleet
from amr_twin.cli.menu import client
from amr_twin.cli.live_options import LiveCommand
from amr_twin.cli.options import ConfigOpt, ParamsOpt, SetOpt
from amr_twin.cli.path_options import CheckedGroup
from amr_twin.ros1 import remapping


class _App(typer.Typer):
    """The typer app, with the parser's usage errors printed as one line (exit 2)."""

    def __call__(self, *args, **kwargs):
        if "standalone_mode" in kwargs:
            return super().__call__(*args, **kwargs)
        argv = kwargs.get("args", args[0] if args else None)
        # Start-up allocates about a million objects (numpy, mujoco, pydantic, typer), which the
        # default thresholds scan over and over, and the interpreter scans them all once more at
        # exit: a 1 s run spent ~0.1 s of its 0.9 s CPU there. Rarer collections until the command's
        # parameters are loaded (amr_twin.cli.common.started), and the survivors frozen before exit
        # (files are closed, atexit handlers still run).
        start_up()
        argv, ros_args = remapping.split(sys.argv[1:] if argv is None else list(argv))
        bad = next(filter(None, map(remapping.problem, ros_args)), None)
        if bad:
            typer.echo(f"error: {bad}", err=True)
            sys.exit(2)
        remapping.keep(
            ros_args
        )  # roslaunch's __name:=, __log:=, remaps: for the ROS 1 node (amr_twin.ros1.remapping)
        kwargs["args"], args = argv, ()
        try:
            with self._only_group(argv):
                code = super().__call__(*args, standalone_mode=False, **kwargs)
        except _click_errors.UsageError as exc:
            where = exc.ctx.command_path if exc.ctx is not None else "amr-twin"
            hint = _misplaced(exc) or f" (see {where} --help)"
            typer.echo(
                f"error: {where}: "
                f"{_missing_command(exc) or _plain(' '.join(exc.format_message().split()))}{hint}",
                err=True,
            )
            sys.exit(2)
        except _click_errors.ClickException as exc:
            typer.echo(f"error: {' '.join(exc.format_message().split())}", err=True)
            sys.exit(exc.exit_code)
        except typer.Abort:
            typer.echo("aborted", err=True)
            sys.exit(130)
        finally:
            gc.freeze()
        sys.exit(code if isinstance(code, int) else 0)

    @contextlib.contextmanager
    def _only_group(self, argv: list[str]):
        """While a command of one group runs (``amr-twin run linear ...``), only that group is
        built: typer turns every registered command into click's when called (~25 ms of
        start-up for all of them, ~7 ms for ``run``). Anything else (top-level help, a
        top-level command, a name that is no group) builds them all."""
        first = argv[0] if argv else ""
        groups = [g for g in self.registered_groups if g.name == first]
        if len(groups) != 1:
            yield
            return
        saved = self.registered_commands, self.registered_groups
        self.registered_commands, self.registered_groups = [], groups
        try:
            yield
        finally:
            self.registered_commands, self.registered_groups = saved


_PARSER_WORDS = {
    "Input should be a valid integer, unable to parse string as an "
    "integer": "expects a whole number",
    "Input should be a valid integer, got a number with a fractional "
    "part": "expects a whole number",
    "Input should be a valid number, unable to parse string as a number": "expects a number",
    "Input should be a valid boolean, unable to interpret input": "expects true or false",
}
"""typer's (pydantic's) words for a value of the wrong type, and the project's."""


def _plain(message: str) -> str:
    """A usage error's message in the project's words (:data:`_PARSER_WORDS`)."""
    for theirs, ours in _PARSER_WORDS.items():
        message = message.replace(theirs, ours)
    return message


def _missing_command(exc) -> str | None:
    """For a group given no command: which it has."""
    commands = getattr(exc.ctx.command, "commands", None) if exc.ctx is not None else None
    if not commands or exc.format_message() != "Missing command.":
        return None
    return f"give a command: {', '.join(commands)}"


def _misplaced(exc) -> str | None:
    """For an option given to a group that belongs to its commands: where it goes."""
    name = getattr(exc, "option_name", None)
    if (
        "given twice" in exc.format_message()
    ):  # amr_twin.cli.path_options._once: the option is in its place
        return None
    group = getattr(exc.ctx, "command", None) if exc.ctx is not None else None
    parent = exc.ctx.parent if exc.ctx is not None else None
    if (
        name
        and parent is not None
        and any(name in p.opts for p in getattr(parent.command, "params", []))
    ):
        return (
            f": {name} is an option of {parent.command_path}; put it before {exc.ctx.info_name!r}"
        )
    commands = getattr(group, "commands", None)
    if not name or not commands:
        return None
    owners = sorted(
        cmd for cmd, c in commands.items() if any(name in p.opts for p in getattr(c, "params", []))
    )
    if not owners:
        return None
    return (
        f": {name} is an option of {' and '.join(owners)}; put it after the command, "
        f"e.g. {exc.ctx.command_path} {owners[0]} {name} ..."
    )


app = _App(
    cls=CheckedGroup,
    add_completion=False,
    no_args_is_help=True,
    help="amr-twin: headless MuJoCo digital twin of the thesis AMR.",
)


def _parse_xy(text: Optional[str]) -> Optional[list[float]]:
    if text is None:
        return None
    try:
        x, y = (float(v) for v in text.split(","))
    except ValueError:
        fail(f"--payload-xy {text!r}: expected X,Y in metres, e.g. 0.1,-0.05")
    if not (math.isfinite(x) and math.isfinite(y)):
        fail(f"--payload-xy {text!r}: must be finite numbers")
    return [x, y]


@app.command()
def model(
    payload_kg: Optional[float] = typer.Option(None, help="Payload mass, kg (0: none)."),
    payload_xy: Optional[str] = typer.Option(
        None, help="Payload centre on the deck, X,Y in metres."
    ),
    export_urdf: Optional[Path] = typer.Option(None, help="Write the generated URDF here."),
    export_mjcf: Optional[Path] = typer.Option(None, help="Write the generated robot MJCF here."),
    as_json: bool = typer.Option(
        False, "--json", help="Print the model summary as one JSON object."
    ),
    config: Optional[Path] = ConfigOpt,
    params: Optional[Path] = ParamsOpt,
    set_: Optional[list[str]] = SetOpt,
) -> None:
    """Build the robot model; export URDF/MJCF; print mass, static loads and tip margin."""
    from amr_twin.model import build as build_mod
    from amr_twin.model.statics import describe

    extra = {}
    if payload_kg is not None:
        if not math.isfinite(payload_kg):
            fail(f"--payload-kg {payload_kg}: must be a finite number")
        extra["payload.mass_kg"] = payload_kg
    xy = _parse_xy(payload_xy)
    if xy is not None:
        extra["payload.xy_m"] = xy
    from amr_twin.recording.outputs import OutputError, check_outputs

    try:
        check_outputs(files={"--export-urdf": export_urdf, "--export-mjcf": export_mjcf})
    except OutputError as exc:
        fail(str(exc))
    cfg = _config(config, params, set_, extra)
    if (
        xy is not None and cfg.payload.mass_kg == 0
    ):  # ignored (and not checked against the deck), exit 0
        fail(
            f"--payload-xy {payload_xy}: there is no payload to place (payload.mass_kg is 0): "
            f"give --payload-kg"
        )

    def work():
        if export_urdf or export_mjcf:
            build_mod.export(cfg, export_urdf, export_mjcf)
        info = describe(cfg)
        if as_json:
            typer.echo(json.dumps(info))
        else:
            typer.echo(
                f"total mass {info['total_mass_kg']:.2f} kg, tip margin "
                f"{info['tip_margin_m']:.3f} m"
            )
            for name, load in info["static_load_n"].items():
                typer.echo(f"  {name:20s} {load:8.2f} N")

    _guard(work)


@app.command()
def bench(
    as_json: bool = typer.Option(False, "--json", help="Print one JSON object."),
    sim_s: float = typer.Option(16.0, help="Simulated seconds per measurement."),
    suites: bool = typer.Option(
        False,
        "--suites",
        help="Also time what users wait for: start-up, chapter 5 "
        "with --jobs 1 and N, a 100-point sweep, .rrd writing, fusion (several minutes).",
    ),
    jobs: Optional[int] = typer.Option(
        None, "--jobs", help="Worker processes for --suites (default: the usable cores)."
    ),
    config: Optional[Path] = ConfigOpt,
    params: Optional[Path] = ParamsOpt,
    set_: Optional[list[str]] = SetOpt,
) -> None:
    """Measure the twin against one bare-physics floor (CPU time, interleaved rounds, spread)."""
    from amr_twin.bench.figures import report_lines, run_benchmarks
    from amr_twin.base.process_pool import check_jobs

    try:
        jobs = check_jobs(jobs)
    except ValueError as exc:
        fail(str(exc))
    from amr_twin.sim.bounds import MIN_RUN_S

    if not (MIN_RUN_S <= sim_s <= 1000):  # 1e-300 s divided by zero
        fail(f"--sim-s {sim_s:g}: must be in [{MIN_RUN_S:g}, 1000] s")
    cfg = _config(config, params, set_)

    def say(text: str) -> None:
        typer.echo(f"bench: {text}", err=True)

    def measure() -> dict:
        figures = run_benchmarks(cfg, sim_s=sim_s, say=say if suites else lambda text: None)
        if suites:
            from amr_twin.bench.suites import suite_figures

            figures["suites"] = suite_figures(cfg, jobs=jobs, progress=say)
        return figures

    result = _guard(measure)
    if as_json:
        typer.echo(json.dumps(result))
    else:
        for line in report_lines(result):
            typer.echo(line)
        for key, value in result.get("suites", {}).items():
            typer.echo(f"{key:32s} {value}")


@app.command()
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


app.add_typer(run_group.app, name="run")
app.add_typer(experiment_group.app, name="experiment")
app.add_typer(sweep_group.app, name="sweep")
app.command(name="client", cls=LiveCommand)(client)
app.command(name="fleet")(fleet)


def main() -> None:  # pragma: no cover - console entry
    app()


if __name__ == "__main__":  # pragma: no cover
    sys.exit(app())
