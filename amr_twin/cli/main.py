"""The ``amr-twin`` command line (typer).

Every command takes the parameter file, an override YAML and ``--set key=value``.
Bad input ends with one line on stderr naming the field (or the file, or the
option) and what is allowed, exit code 2, checked before the work starts, and no
output file written; a usage error of the parser (an unknown option, a value that
is not a number) is one line too. A file that cannot be written at the end (a full
disk) is one line and exit code 1, with none of the command's files left half-made.
"""

from __future__ import annotations

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

from amr_twin.cli import experiment as experiment_group
from amr_twin.cli import run as run_group
from amr_twin.cli import sweep as sweep_group
from amr_twin.cli.app import App
from amr_twin.cli.calibrate import calibrate
from amr_twin.cli.common import _config, _guard, fail
from amr_twin.cli.fleet import fleet
from amr_twin.cli.menu import client
from amr_twin.cli.live_options import LiveCommand
from amr_twin.cli.options import ConfigOpt, ParamsOpt, SetOpt
from amr_twin.cli.path_options import CheckedGroup


app = App(
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
    with_fleet: bool = typer.Option(
        False,
        "--fleet",
        help="Also time 1, 4 and 8 robots navigating in one world (EKF + MPPI): CPU ms per "
        "robot-second, its ratio to one robot, the real-time factor (a few minutes).",
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
        if with_fleet:
            from amr_twin.bench.fleet import fleet_figures

            figures["fleet"] = fleet_figures(cfg)
        return figures

    result = _guard(measure)
    if as_json:
        typer.echo(json.dumps(result))
    else:
        for line in report_lines(result):
            typer.echo(line)
        for key, value in {**result.get("suites", {}), **result.get("fleet", {})}.items():
            typer.echo(f"{key:32s} {value}")


app.command(name="calibrate")(calibrate)
app.add_typer(run_group.app, name="run")
app.add_typer(experiment_group.app, name="experiment")
app.add_typer(sweep_group.app, name="sweep")
app.command(name="client", cls=LiveCommand)(client)
app.command(name="fleet", cls=LiveCommand)(fleet)


def main() -> None:  # pragma: no cover - console entry
    app()


if __name__ == "__main__":  # pragma: no cover
    sys.exit(app())
