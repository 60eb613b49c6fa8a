"""``amr-twin run`` and ``amr-twin client``: the high-level control as in ROS.

``amr-twin run linear|angular|motor|stop`` sends one wheel_Command_Client call at
t = 0 and runs the twin for ``--duration-s``; ``amr-twin run --mission FILE`` runs
a timed list of them (format in :mod:`amr_twin.assembly.mission`). The shared options
(:mod:`amr_twin.cli.run_options`) go before or after the command kind. ``--csv`` writes
the time series, ``--json`` prints one summary object, ``--fault`` injects faults
(:mod:`amr_twin.sim.faults`), ``--stop-on-collision`` ends the run at the first
collision (:mod:`amr_twin.sim.collisions`).

Everything is checked before the model is built: numbers, faults, the start pose
format, every output path (:mod:`amr_twin.recording.outputs`). Exit codes: 0 done (collisions
are reported, on stderr too); 1 the client refused a command (the thesis' message
on stderr) or an output could not be written; 2 bad input, one line; 3 the
simulation diverged; 4 stopped by a collision (``--stop-on-collision``). The
output files appear together at the end, or none of them.
"""

from __future__ import annotations

from pathlib import Path
from typing import Optional

import typer

from amr_twin.cli.common import fail
from amr_twin.cli.goto import goto, run_goals
from amr_twin.cli.live_options import LiveGroup
from amr_twin.cli.run_options import RunOptions, _given, shared
from amr_twin.cli.run_execution import execute, finite


def Command(*args, **kwargs):  # noqa: N802 - amr_twin.assembly.command.Command, imported when a run starts
    from amr_twin.assembly.command import Command as RunCommand

    return RunCommand(*args, **kwargs)


def one(opts: RunOptions, command_factory) -> None:
    """Run the single command ``command_factory()`` builds (its ValueError refused in one line)."""
    try:
        command = command_factory()
    except ValueError as exc:
        fail(str(exc))
    execute(opts, [(0.0, command)], True)


app = typer.Typer(
    cls=LiveGroup,
    add_completion=False,
    no_args_is_help=False,
    help="Run wheel commands on the twin, as wheel_Command_Client does. The options "
    "below go before or after the command kind.",
)
"""``amr-twin run``: linear, angular, motor, stop, goto (:func:`amr_twin.cli.goto.goto`) or
--mission."""


@app.callback(invoke_without_command=True)
@shared(fail)
def run(
    opts: RunOptions,
    ctx: typer.Context,
    mission: Optional[Path] = typer.Option(
        None,
        "--mission",
        help="Mission YAML (see amr_twin/assembly/mission.py); "
        "its faults: list adds to --fault, its actors: to --actor.",
    ),
) -> None:
    """Run a command kind (linear, angular, motor, stop) or a --mission file."""
    if ctx.invoked_subcommand is not None:
        if mission is not None:
            fail("--mission and a command kind cannot be combined")
        return
    if mission is None:
        fail("give a command (linear, angular, motor, stop) or --mission FILE")
    from amr_twin.assembly.mission import MissionError, load_mission_file

    try:
        plan = load_mission_file(mission)
    except MissionError as exc:
        fail(str(exc))
    if plan.goals:
        nav = {"map": None, "localisation": "ekf", "controller": "mppi", **plan.navigation}
        if not _given(ctx, "firmware"):
            opts.firmware = "improved"  # as run goto (amr_twin/cli/goto.py)
        run_goals(
            opts,
            plan.goals,
            nav,
            opts.duration_s if opts.duration_s is not None else plan.duration_s,
            plan.faults,
            plan.actors,
        )
        return
    execute(opts, plan.steps, False, plan.duration_s, plan.faults, plan.actors)


@app.command()
@shared(fail)
def linear(
    opts: RunOptions,
    speed_m_s: Optional[float] = typer.Option(None, "--speed-m-s", help="m/s; negative: backward."),
) -> None:
    """Linear motion: both wheels at the same speed (listing 4.4)."""
    speed = finite("--speed-m-s", speed_m_s)
    one(opts, lambda: Command("linear", speed_m_s=speed))


@app.command()
@shared(fail)
def angular(
    opts: RunOptions,
    speed_deg_s: Optional[float] = typer.Option(None, "--speed-deg-s", help="deg/s, CCW +."),
    icc_m: Optional[float] = typer.Option(None, "--icc-m", help="ICC distance, m, + to the left."),
) -> None:
    """Rotation about an ICC (listing 4.5; REP-103 signs)."""
    speed, icc = finite("--speed-deg-s", speed_deg_s), finite("--icc-m", icc_m)
    one(opts, lambda: Command("angular", speed_deg_s=speed, icc_m=icc))


@app.command()
@shared(fail)
def motor(
    opts: RunOptions,
    wheel: Optional[str] = typer.Option(None, "--wheel", help="left or right."),
    direction: Optional[str] = typer.Option(None, "--direction", help="forward or backward."),
    speed_m_s: Optional[float] = typer.Option(None, "--speed-m-s", help="Rim speed, m/s, >= 0."),
) -> None:
    """One wheel driven, the other free-spinning (fig. 3.6)."""
    if wheel is None:
        fail("--wheel is required (left or right)")
    if direction is None:
        fail("--direction is required (forward or backward)")
    speed = finite("--speed-m-s", speed_m_s)
    one(opts, lambda: Command("motor", wheel=wheel, direction=direction, speed_m_s=speed))


@app.command()
@shared(fail)
def stop(opts: RunOptions) -> None:
    """Brake both wheels (fig. 3.7)."""
    one(opts, lambda: Command("stop"))


app.command("goto")(goto)
