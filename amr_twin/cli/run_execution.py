"""A run of ``amr-twin run``: every option checked before the model is built, then the twin run
(served live or on a ROS 1 graph: :mod:`amr_twin.cli.live_run`) and its outputs written together,
with the exit codes of :mod:`amr_twin.cli.run`.
"""

from __future__ import annotations

import json
import logging
import math
from typing import Optional

import click
import typer

from amr_twin.cli.actor_options import checked_actors
from amr_twin.cli.common import _config, _guard, _start_pose, fail
from amr_twin.cli.live_options import checked_live
from amr_twin.cli.options import checked_firmware, checked_seed
from amr_twin.cli.ros1_options import checked_ros1
from amr_twin.cli.run_options import RunOptions, _given
from amr_twin.cli.live_run import run_live
from amr_twin.sim.bounds import duration_problem
from amr_twin.recording.run_report import collision_warning, csv_text, text_lines
from amr_twin.recording.run_summary import summary

DEFAULT_RUN_S = 10.0
EXIT_COLLISION = 4


def finite(name: str, value: Optional[float], required: bool = True) -> Optional[float]:
    if value is None:
        if required:
            fail(f"{name} is required")
        return None
    if not math.isfinite(value):
        fail(f"{name} {value}: must be a finite number")
    return value


def _duration(opts: RunOptions, default_s: float) -> float:
    if opts.duration_s == math.inf:  # until stopped: Ctrl-C, SIGTERM (roslaunch), run_live
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
    duration_s = finite("--duration-s", opts.duration_s, required=False)
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
    if finite("--payload-kg", opts.payload_kg, required=False) is not None:
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
                res = run_live(
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
