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

import json
import logging
import math
from pathlib import Path
from typing import Optional

import click
import typer

from amr_twin.cli.actor_options import checked_actors
from amr_twin.cli.common import _config, _guard, _start_pose, fail
from amr_twin.cli.goto import goto, run_goals
from amr_twin.cli.live_options import LiveGroup, checked_live
from amr_twin.cli.options import checked_firmware, checked_seed
from amr_twin.cli.ros1_options import checked_ros1
from amr_twin.cli.run_options import RunOptions, _given, shared
from amr_twin.sim.bounds import duration_problem
from amr_twin.recording.run_report import collision_warning, csv_text, text_lines
from amr_twin.recording.run_summary import summary

DEFAULT_RUN_S = 10.0
EXIT_COLLISION = 4


def _finite(name: str, value: Optional[float], required: bool = True) -> Optional[float]:
    if value is None:
        if required:
            fail(f"{name} is required")
        return None
    if not math.isfinite(value):
        fail(f"{name} {value}: must be a finite number")
    return value


def _duration(opts: RunOptions, default_s: float) -> float:
    if opts.duration_s == math.inf:  # until stopped: Ctrl-C, SIGTERM (roslaunch), _run_live
        if not (opts.ros1 or opts.live is not None):
            fail(
                "--duration-s inf: a run until stopped is for the graph or a live view: give "
                "--ros1 or --live"
            )
        if opts.record is not None or opts.mcap is not None:
            fail(
                "--duration-s inf: --record and --mcap keep every message until the run ends: "
                "give a finite "
                "--duration-s"
            )
        return math.inf
    duration_s = _finite("--duration-s", opts.duration_s, required=False)
    duration_s = default_s if duration_s is None else duration_s
    if duration_problem(duration_s):
        fail(f"--duration-s {duration_s:g}: {duration_problem(duration_s)}")
    return duration_s


def execute(
    opts: RunOptions,
    steps,
    single: bool,
    default_s: float = DEFAULT_RUN_S,
    mission_faults: tuple[str, ...] = (),
    mission_actors: tuple = (),
) -> None:
    """Check everything, run ``steps`` and report; exits non-zero on a refusal or a stop."""
    from amr_twin.sim.faults import FaultError, parse_faults
    from amr_twin.assembly.twin import TwinOptions
    from amr_twin.recording.outputs import OutputError, check_outputs
    from amr_twin.recording.run import run_mission

    duration_s = _duration(opts, default_s)
    last_s = max((t for t, _ in steps), default=0.0)
    if last_s > duration_s:
        fail(f"--duration-s {duration_s:g}: ends before the mission's last step, at {last_s:g} s")
    checked_seed(opts.seed, fail)
    firmware = checked_firmware(opts.firmware, opts.sketch, fail)
    extra = {}
    if _finite("--payload-kg", opts.payload_kg, required=False) is not None:
        extra["payload.mass_kg"] = opts.payload_kg
    start = _start_pose(opts.start)
    try:
        faults = parse_faults(
            list(mission_faults) + list(opts.fault), duration_s=duration_s, sensors=opts.sensors
        )
    except FaultError as exc:
        fail(str(exc))
    try:
        check_outputs(files={"--csv": opts.csv, "--record": opts.record, "--mcap": opts.mcap})
    except OutputError as exc:
        fail(str(exc))
    paced = opts.ros1 or opts.serial_pty is not None
    live = checked_live(
        opts.live, opts.host, opts.port, opts.web_port, opts.rate, fail, paced=paced
    )
    ros1, avr_params, rate = checked_ros1(
        opts.ros1, opts.roscore, opts.serial_pty, firmware, live is not None, opts.rate, fail
    )
    if opts.serial_pty is not None:
        if not (single and len(steps) == 1 and steps[0][1].kind == "stop"):
            fail(
                "--serial-pty: the board's serial port is your rosserial host's: drive it from "
                "ROS and give "
                "`run stop` (the board starts braked)"
            )
        from amr_twin.controllers.firmware import check_avr

        try:
            check_avr(firmware, avr_params)
        except ValueError as exc:
            fail(str(exc))
        steps = []  # the stop is the board's state at power-up: nothing is sent on its serial port
    calibration = None
    if opts.odometry is not None:
        from amr_twin.controllers.odometry_calibration import load

        try:
            calibration = load(opts.odometry)
        except ValueError as exc:
            fail(str(exc))
    recording = opts.record is not None or opts.mcap is not None
    from amr_twin.cli.checks import check_memory

    if duration_s != math.inf:  # until stopped: ~0.11 MB a simulated second, amr_twin.sim.bounds
        check_memory(
            duration_s,
            fail,
            recorded=recording,
            sensors=opts.sensors,
            rerun=opts.record is not None,
        )
    cfg = _config(opts.config, opts.params, opts.set_, extra)
    actors = checked_actors(opts, mission_actors, cfg, start)
    # --ros1 --sensors: the navigation stack as move_base (amr_twin/ros1/navigation_setup.py)
    navigation = None
    if ros1 is not None and opts.sensors and opts.serial_pty is None:
        from amr_twin.ros1.navigation_setup import RunNavigation

        try:
            navigation = RunNavigation.checked(cfg, opts.world, start)
        except (
            ValueError
        ) as exc:  # a world without a map, ROS 1 without actionlib: the run goes on without it
            typer.echo(f"ros1: no move_base on this run: {exc}", err=True)
        ctx = click.get_current_context(silent=True)
        if navigation is not None and not any(
            _given(c, "firmware") for c in (ctx, ctx and ctx.parent)
        ):
            firmware = (
                "improved"  # as run goto: the faithful one restarts its ramps on every cmd_vel
            )
    options = TwinOptions(
        firmware=firmware,
        seed=opts.seed,
        world=opts.world,
        sensors=("imu", "lidar") if opts.sensors else (),
        start_xy_yaw=start,
        faults=faults,
        stop_on_collision=opts.stop_on_collision,
        visuals=recording or live is not None,
        firmware_params=avr_params,
        actors=actors,
        odometry_calibration=calibration,
    )
    # the client's refusals are printed below, once
    logging.getLogger("amr_twin.controllers.wheel_command").addHandler(logging.NullHandler())

    def work():
        from amr_twin.base.atomic_file import all_or_nothing
        from amr_twin.assembly.twin import Twin

        twin = Twin(cfg, options)
        if opts.serial_pty is not None:
            typer.echo(
                f"serial-pty: the board's serial port is {opts.serial_pty} (-> "
                f"{twin.firmware.serial.device}), "
                f"paced at {rate:g}x real time",
                err=True,
            )
        try:
            if recording:
                from amr_twin.recording.rerun_capture import attach

                attach(twin)
            run_steps = steps
            if navigation is not None:
                navigation.attach(twin, opts.seed)
                run_steps = navigation.yielding(steps, say=lambda line: typer.echo(line, err=True))
            if live is None and ros1 is None:
                res = run_mission(cfg, steps, duration_s, options, twin=twin)
            else:
                res = _run_live(
                    twin,
                    live,
                    lambda: run_mission(cfg, run_steps, duration_s, options, twin=twin),
                    ros1,
                    rate,
                    navigation,
                )
        finally:
            if opts.serial_pty is not None:
                fw = twin.firmware
                typer.echo(
                    f"serial-pty: the board answered {fw.negotiations} topic negotiation(s) and "
                    f"asked the "
                    f"time {fw.time_requests} time(s); {fw.serial.bytes_in} bytes in, "
                    f"{fw.serial.bytes_out} out, "
                    f"{fw.serial.bytes_dropped} dropped; {fw.pacer.lag_resets} lag reset(s)",
                    err=True,
                )
                fw.close()  # the pseudo-terminal's link goes with the run
        with all_or_nothing():
            if recording:
                from amr_twin.recording.rerun_log import record_run

                record_run(twin, rrd_path=opts.record, mcap_path=opts.mcap, result=res)
            if opts.csv is not None:
                from amr_twin.base.atomic_file import write_text

                write_text(opts.csv, csv_text(res.series))
        return res, twin.start_xy_yaw

    result, start_pose = _guard(work)
    info = summary(result, single, start_pose)
    if opts.as_json:
        typer.echo(json.dumps(info.as_json()))
    else:
        for line in text_lines(result, info):
            typer.echo(line)
    warning = collision_warning(info)
    if warning:
        typer.echo(warning, err=True)
    for message in result.errors:
        typer.echo(message, err=True)
    if info.code != 0:
        raise typer.Exit(1)
    if result.halted:
        raise typer.Exit(EXIT_COLLISION)


def _run_live(twin, live, run, ros1=None, rate: float = 1.0, navigation=None):
    """``run()`` with ``twin`` served live (amr_twin.live.session) and/or on a ROS 1 graph
    (amr_twin.ros1.session), with ``navigation`` (amr_twin.ros1.navigation_setup) as move_base
    there. SIGINT (Ctrl-C) or SIGTERM (roslaunch sends both) ends the run at the twin's next event
    and the outputs are written; a second one ends it at once, without them (exit 130)."""
    import signal

    say = lambda line: typer.echo(line, err=True)  # noqa: E731
    signals: list[int] = []

    def on_signal(signum, _frame):
        if signals:
            raise KeyboardInterrupt
        signals.append(signum)
        twin.stop()

    before = {s: signal.signal(s, on_signal) for s in (signal.SIGINT, signal.SIGTERM)}
    session = ros = None
    if live is not None:
        from amr_twin.live.session import LiveSession

        session = LiveSession(twin, live, say=say)
        pacer = session.pacer
    else:
        from amr_twin.controllers.diff_drive import DiffDriveNode
        from amr_twin.live.pacer import Pacer
        from amr_twin.live.session import CMD_TIMEOUT_S

        from amr_twin.ros1.session import pacer_tick_us

        pacer = Pacer(twin, rate, pacer_tick_us(rate))
        DiffDriveNode(twin.bus, twin.clock, twin.client, cmd_timeout_s=CMD_TIMEOUT_S)
    try:
        if ros1 is not None:
            from amr_twin.ros1.session import Ros1Session

            ros = Ros1Session(twin, pacer, ros1, say=say)
            if navigation is not None:
                navigation.serve(twin, pacer, say=say)
        result = run()
        if signals:
            say(
                f"stopped by {signal.Signals(signals[0]).name} at t={twin.t_s:.2f} s simulated; "
                f"writing the outputs"
            )
        return result
    except KeyboardInterrupt:
        fail(f"interrupted at t={twin.t_s:.2f} s simulated; no output written", code=130)
    finally:
        for s, handler in before.items():
            signal.signal(s, handler)
        (session or pacer).close()
        if ros is not None:
            ros.close()
        for name, sink in (
            ("live", session.sink if session else None),
            ("ros1", ros.bridge if ros else None),
        ):
            dropped = getattr(sink, "dropped", 0)
            if dropped:
                typer.echo(
                    f"{name}: {dropped} message(s) from clients dropped (see the warnings above)",
                    err=True,
                )


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
    speed = _finite("--speed-m-s", speed_m_s)
    one(opts, lambda: Command("linear", speed_m_s=speed))


@app.command()
@shared(fail)
def angular(
    opts: RunOptions,
    speed_deg_s: Optional[float] = typer.Option(None, "--speed-deg-s", help="deg/s, CCW +."),
    icc_m: Optional[float] = typer.Option(None, "--icc-m", help="ICC distance, m, + to the left."),
) -> None:
    """Rotation about an ICC (listing 4.5; REP-103 signs)."""
    speed, icc = _finite("--speed-deg-s", speed_deg_s), _finite("--icc-m", icc_m)
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
    speed = _finite("--speed-m-s", speed_m_s)
    one(opts, lambda: Command("motor", wheel=wheel, direction=direction, speed_m_s=speed))


@app.command()
@shared(fail)
def stop(opts: RunOptions) -> None:
    """Brake both wheels (fig. 3.7)."""
    one(opts, lambda: Command("stop"))


app.command("goto")(goto)
