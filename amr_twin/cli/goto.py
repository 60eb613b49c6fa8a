"""``amr-twin run goto --goal X,Y[,YAW_DEG]`` and navigation missions (``goals:``): the robot sent
to goals.

Everything is checked before the model is built, each refusal one line and exit 2: the goal's
numbers, the map (``--map``, a map_server YAML), the localisation and the controller, and each
goal against the map from where the robot will be (the start, then the goal before it): off
the map, inside an obstacle or closer to one than the robot's half width, or cut off from it.
Then the navigation stack (amr_twin/navigation/) drives the twin, a progress line on stderr on long
runs (:mod:`amr_twin.cli.goto_console`). A goal is reached only if the TRUE pose ends within the
goal tolerances (:mod:`amr_twin.navigation.goal_truth`); one not reached (the truth missed it, a
path that became blocked, no progress after the recoveries, the time limit) is reported in one
line and the command exits :data:`EXIT_NOT_REACHED`. Ctrl-C cancels the goals: the robot stops,
the outputs are written, exit :data:`~amr_twin.cli.goto_console.EXIT_CANCELED`; a second Ctrl-C
quits at once (130, nothing written). ``--stop-on-collision``'s stop exits 4.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Optional

import typer

from amr_twin.cli.actor_options import checked_actors
from amr_twin.cli.common import _config, _guard, _start_pose, fail
from amr_twin.cli.goto_console import EXIT_CANCELED, GotoConsole
from amr_twin.cli.goto_options import GOTO_DEFAULTS, RUN_OVERRIDES, checked_goals, parse_goal
from amr_twin.cli.goto_report import clearance, report
from amr_twin.cli.run_options import RunOptions, shared
from amr_twin.navigation.registries import CONTROLLERS, LOCALISATIONS, help_text

EXIT_NOT_REACHED = 5
EXIT_COLLISION = 4


def run_goals(
    opts,
    goals,
    nav: dict,
    duration_s: Optional[float],
    mission_faults: tuple = (),
    mission_actors: tuple = (),
    settings: dict | None = None,
) -> None:
    """Check, navigate to ``goals`` in turn, print and write the outputs, exit as the module
    docstring says.

    ``mission_actors``: the mission's people and pallet jacks (``--actor`` and ``--actors-random``
    add to them, :func:`amr_twin.cli.actor_options.checked_actors`); ``settings``: parameter file
    keys the command's options set (goal tolerances, inflation)."""
    from dataclasses import replace

    from amr_twin.cli.options import checked_firmware
    from amr_twin.recording.outputs import OutputError, check_outputs
    from amr_twin.sim.faults import FaultError, parse_faults
    from amr_twin.assembly.twin import TwinOptions

    firmware = checked_firmware(opts.firmware, opts.sketch, fail)
    if (
        opts.serial_pty
    ):  # the board would be driven from ROS; here the navigation stack drives the twin
        fail(
            "--serial-pty is not available with goals (run goto, a mission's goals:): use it "
            "with a command kind "
            "or a mission's steps"
        )
    if duration_s is not None and not (math.isfinite(duration_s) and 0.1 <= duration_s <= 3600):
        fail(f"--duration-s {duration_s:g}: must be in [0.1, 3600] s (the time limit of the goals)")
    try:
        faults = parse_faults(
            list(mission_faults) + list(opts.fault), duration_s=duration_s or 3600.0, sensors=True
        )
        check_outputs(files={"--csv": opts.csv, "--record": opts.record, "--mcap": opts.mcap})
    except (FaultError, OutputError) as exc:
        fail(str(exc))
    from amr_twin.cli.live_options import checked_live

    live = checked_live(
        opts.live, opts.host, opts.port, opts.web_port, opts.rate, fail, paced=opts.ros1
    )
    from amr_twin.cli.ros1_options import checked_ros1

    ros1, _avr, rate = checked_ros1(
        opts.ros1, opts.roscore, None, firmware, live is not None, opts.rate, fail
    )
    if ros1 is not None:
        from amr_twin.ros1.navigation_server import missing

        if missing():
            fail(f"--ros1 with goals: {missing()}")
    extra = {"payload.mass_kg": opts.payload_kg} if opts.payload_kg is not None else {}
    cfg = _config(opts.config, opts.params, opts.set_, {**extra, **(settings or {})})
    static = _guard(lambda: checked_goals(cfg, opts, goals, nav))
    recording = opts.record is not None or opts.mcap is not None
    start = _start_pose(opts.start)
    actors = checked_actors(opts, tuple(mission_actors), cfg, start)
    calibration = None
    if opts.odometry is not None:  # it was ignored: the odometry kept the nominal geometry
        from amr_twin.controllers.odometry_calibration import load

        try:
            calibration = load(opts.odometry)
        except ValueError as exc:
            fail(str(exc))
    options = TwinOptions(
        firmware=firmware,
        seed=opts.seed,
        world=opts.world,
        start_xy_yaw=start,
        faults=faults,
        stop_on_collision=opts.stop_on_collision,
        visuals=recording or live is not None,
        actors=actors,
        odometry_calibration=calibration,
    )
    say = lambda line: typer.echo(line, err=True)  # noqa: E731
    console = GotoConsole(say)

    def work():
        from amr_twin.navigation.navigation_run import navigate
        from amr_twin.navigation.stack import NavigationOptions
        from amr_twin.base.atomic_file import all_or_nothing

        held = {}

        def on_twin(twin):
            held["twin"] = twin
            if recording:
                from amr_twin.recording.rerun_capture import attach

                attach(twin)
            if live is not None:  # the live session brings its cmd_vel node (and the pacing)
                from amr_twin.live.session import LiveSession

                held["live"] = LiveSession(twin, live, say=say)
            if (
                ros1 is not None
            ):  # the graph, and the navigator as move_base (amr_twin/ros1/navigation_setup.py)
                from amr_twin.ros1.navigation_setup import GoalsOnGraph

                held["ros1"] = GoalsOnGraph(
                    twin, cfg, static, ros1, rate, held["live"].pacer if live else None, say
                )

        nav_opts = NavigationOptions(
            goals=tuple(goals),
            map_yaml=nav.get("map"),
            localisation=nav["localisation"],
            controller=nav["controller"],
            seed=opts.seed,
            timeout_s=duration_s,
        )
        try:
            with console:
                try:
                    run = navigate(
                        cfg,
                        replace(options),
                        nav_opts,
                        static=static,
                        on_twin=on_twin,
                        progress=console,
                        publish=recording or live is not None or ros1 is not None,
                        drive=live is None,
                    )
                finally:
                    if "live" in held:
                        held["live"].close()
                    if "ros1" in held:
                        held["ros1"].close()
                with all_or_nothing():
                    if recording:
                        from amr_twin.recording.rerun_log import record_run

                        record_run(held["twin"], rrd_path=opts.record, mcap_path=opts.mcap)
                    if opts.csv is not None:
                        from amr_twin.base.atomic_file import write_text
                        from amr_twin.recording.recorder import recorder_of
                        from amr_twin.recording.run_report import csv_text

                        write_text(opts.csv, csv_text(recorder_of(held["twin"]).series()))
        except KeyboardInterrupt:
            t = f" at t={held['twin'].t_s:.2f} s simulated" if "twin" in held else ""
            fail(f"interrupted{t}; no output written", code=130)
        from amr_twin.recording.fault_effects import fault_effects
        from amr_twin.recording.recorder import recorder_of

        twin = held["twin"]  # each fault with its effect, as run linear reports it
        return run, fault_effects(
            twin.faults, recorder_of(twin).series()
        ) if twin.faults is not None else []

    run, fault_report = _guard(work)
    report(run, opts.as_json, fault_report, clearance(cfg, opts.world, run))
    if run.collisions:
        typer.echo(
            f"warning: {len(run.collisions)} collision(s), the first at t = "
            f"{run.collisions[0]['t_s']:.2f} s "
            f"with {run.collisions[0].get('world', '?')}",
            err=True,
        )
    if console.canceled_at_s is not None:
        typer.echo(
            f"canceled by Ctrl-C at t = {console.canceled_at_s:.1f} s; the outputs are written",
            err=True,
        )
        raise typer.Exit(EXIT_CANCELED)
    if opts.stop_on_collision and run.collisions:
        raise typer.Exit(EXIT_COLLISION)
    failed = [o for o in run.outcomes if o.status not in ("succeeded", "preempted")]
    if failed:
        typer.echo(f"error: {failed[0].reason}", err=True)
        raise typer.Exit(EXIT_NOT_REACHED)


@shared(fail, overrides=RUN_OVERRIDES)
def goto(
    opts: RunOptions,
    ctx: typer.Context,
    goal: Optional[str] = typer.Option(
        None, "--goal", help="X_M,Y_M[,YAW_DEG] in the map frame (REP-103)."
    ),
    map_: Optional[Path] = typer.Option(
        None,
        "--map",
        help="A map_server YAML (a map the fusion experiment "
        "saved, an imported ROS map); default: the world's true map.",
    ),
    localisation: str = typer.Option("ekf", "--localisation", help=f"{help_text(LOCALISATIONS)}."),
    controller: str = typer.Option("mppi", "--controller", help=f"{help_text(CONTROLLERS)}."),
    xy_tolerance_m: Optional[float] = typer.Option(
        None,
        "--xy-tolerance-m",
        help=f"Goal tolerance, m: the true pose must end this close to the goal "
        f"(default {GOTO_DEFAULTS['xy_tolerance_m']:g}, navigation.navigator.xy_tolerance_m).",
    ),
    yaw_tolerance_deg: Optional[float] = typer.Option(
        None,
        "--yaw-tolerance-deg",
        help=f"Goal heading tolerance, deg, for a goal with a yaw (default "
        f"{GOTO_DEFAULTS['yaw_tolerance_deg']:g}, navigation.navigator.yaw_tolerance_rad 0.25).",
    ),
    inflation_radius_m: Optional[float] = typer.Option(
        None,
        "--inflation-radius-m",
        help=f"How far from obstacles the costmap's cost spreads, m: larger keeps "
        f"the robot nearer the middle of aisles (default {GOTO_DEFAULTS['inflation_radius_m']:g}, "
        "navigation.costmap.inflation_radius_m).",
    ),
) -> None:
    """Navigate to a goal: plan on the map, follow, avoid, recover (amr_twin/navigation/,
    docs/explanation/navigation.md). Success is judged by the true pose; Ctrl-C stops the robot and
    writes the outputs (exit 6)."""
    if goal is None:
        fail("--goal is required (X_M,Y_M or X_M,Y_M,YAW_DEG)")
    settings = {}
    if xy_tolerance_m is not None:
        settings["navigation.navigator.xy_tolerance_m"] = xy_tolerance_m
    if yaw_tolerance_deg is not None:
        if not (math.isfinite(yaw_tolerance_deg) and 0.0 < yaw_tolerance_deg <= 180.0):
            fail(f"--yaw-tolerance-deg {yaw_tolerance_deg:g}: must be in (0, 180] deg")
        settings["navigation.navigator.yaw_tolerance_rad"] = math.radians(yaw_tolerance_deg)
    if inflation_radius_m is not None:
        settings["navigation.costmap.inflation_radius_m"] = inflation_radius_m
    nav = {
        "map": None if map_ is None else str(map_),
        "localisation": localisation,
        "controller": controller,
    }
    run_goals(opts, [parse_goal(goal)], nav, opts.duration_s, settings=settings)
