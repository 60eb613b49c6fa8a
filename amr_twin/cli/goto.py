"""``amr-twin run goto --goal X,Y[,YAW_DEG]`` and navigation missions (``goals:``): the robot sent to goals.

Everything is checked before the model is built, each refusal one line and exit 2: the goal's
numbers, the map (``--map``, a map_server YAML), the localisation and the controller, and each
goal against the map from where the robot will be (the start, then the goal before it): off
the map, inside an obstacle or closer to one than the robot's half width, or cut off from it.
Then the navigation stack (amr_twin/navigation/) drives the twin; a goal it cannot reach (a path
that became blocked, no progress after the recoveries, the time limit) is reported in one line
and the command exits :data:`EXIT_NOT_REACHED`.
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Optional

import typer

from amr_twin.cli.actor_options import checked_actors
from amr_twin.cli.common import _config, _guard, _start_pose, fail
from amr_twin.cli.options import RunOptions, _given, shared

EXIT_NOT_REACHED = 5


def parse_goal(text: str, option: str = "--goal") -> tuple[float, float, float | None]:
    """``X_M,Y_M[,YAW_DEG]`` to ``(x_m, y_m, yaw_rad or None)``; a one-line refusal otherwise."""
    try:
        values = [float(v) for v in text.split(",")]
    except ValueError:
        values = []
    if len(values) not in (2, 3):
        fail(f"{option} {text!r}: expected X_M,Y_M or X_M,Y_M,YAW_DEG, e.g. 10,-4.8,180")
    if not all(math.isfinite(v) and abs(v) <= 1e4 for v in values):
        fail(f"{option} {text!r}: each value must be finite and within +-10000")
    return values[0], values[1], math.radians(values[2]) if len(values) == 3 else None


def _checked(cfg, opts, goals, nav: dict):
    """The static map and the start pose, every goal checked against them (module docstring)."""
    import numpy as np

    from amr_twin.model.worlds import MapError, default_start
    from amr_twin.navigation.footprint import robot_footprint
    from amr_twin.navigation.localisation import SOURCES
    from amr_twin.navigation.planner import GlobalPlanner
    from amr_twin.navigation.stack import CONTROLLERS, load_static_map, make_costmap

    if nav["localisation"] not in SOURCES:
        fail(f"--localisation {nav['localisation']!r}: must be one of {', '.join(SOURCES)}")
    if nav["controller"] not in CONTROLLERS:
        fail(f"--controller {nav['controller']!r}: must be one of {', '.join(CONTROLLERS)}")
    if nav.get("map") and not Path(nav["map"]).is_file():
        fail(f"--map {nav['map']}: no such file (a map_server YAML next to its PGM)")
    try:
        static = load_static_map(cfg, opts.world, nav.get("map"))
    except MapError as exc:
        fail(f"--map {exc}" if nav.get("map") else str(exc))
    start = _start_pose(opts.start) or default_start(opts.world)
    planner = GlobalPlanner(make_costmap(static, robot_footprint(cfg), cfg.navigation))
    here = np.array(start[:2], float)
    if not planner.costmap.cells(here[None])[2][0]:
        of = f"--map {nav['map']}" if nav.get("map") else f"--world {opts.world}"
        fail(f"the start ({here[0]:g}, {here[1]:g}) lies outside the map of {of}: give --start X_M,Y_M,YAW_DEG on it")
    for x, y, yaw in goals:
        name = f"goal {x:g},{y:g}"
        if planner.plan(here, np.array([x, y])) is None:
            fail(f"{name}: {planner.last_error}")
        here = np.array([x, y])
    return static


def run_goals(opts, goals, nav: dict, duration_s: Optional[float], mission_faults: tuple = (),
              mission_actors: tuple = ()) -> None:
    """Check, navigate to ``goals`` in turn, print and write the outputs, exit as the module docstring says.

    ``mission_actors``: the mission's people and pallet jacks (``--actor`` and ``--actors-random``
    add to them, :func:`amr_twin.cli.actor_options.checked_actors`)."""
    from dataclasses import replace

    from amr_twin.cli.options import checked_firmware
    from amr_twin.recording.outputs import OutputError, check_outputs
    from amr_twin.sim.faults import FaultError, parse_faults
    from amr_twin.sim.loop import TwinOptions

    firmware = checked_firmware(opts.firmware, opts.sketch, fail)
    for flag, given in (("--ros1", opts.ros1), ("--roscore", opts.roscore), ("--serial-pty", opts.serial_pty)):
        if given:  # they were ignored: the navigation stack drives the twin here
            fail(f"{flag} is not available with goals (run goto, a mission's goals:): use it with a command kind "
                 "or a mission's steps")
    if duration_s is not None and not (math.isfinite(duration_s) and 0.1 <= duration_s <= 3600):
        fail(f"--duration-s {duration_s:g}: must be in [0.1, 3600] s (the time limit of the goals)")
    try:
        faults = parse_faults(list(mission_faults) + list(opts.fault), duration_s=duration_s or 3600.0, sensors=True)
        check_outputs(files={"--csv": opts.csv, "--record": opts.record, "--mcap": opts.mcap})
    except (FaultError, OutputError) as exc:
        fail(str(exc))
    from amr_twin.cli.options import checked_live
    live = checked_live(opts.live, opts.host, opts.port, opts.web_port, opts.rate, fail)
    extra = {"payload.mass_kg": opts.payload_kg} if opts.payload_kg is not None else {}
    cfg = _config(opts.config, opts.params, opts.set_, extra)
    static = _guard(lambda: _checked(cfg, opts, goals, nav))
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
    options = TwinOptions(firmware=firmware, seed=opts.seed, world=opts.world, start_xy_yaw=start,
                          faults=faults, stop_on_collision=opts.stop_on_collision, visuals=recording or live is not None,
                          actors=actors, odometry_calibration=calibration)

    def work():
        from amr_twin.navigation.stack import NavigationOptions, navigate
        from amr_twin.recording.atomic_file import all_or_nothing

        held = {}

        def on_twin(twin):
            held["twin"] = twin
            if recording:
                from amr_twin.recording.rerun_capture import attach
                attach(twin)
            if live is not None:  # the live session brings its cmd_vel node (and the pacing)
                from amr_twin.live.session import LiveSession
                held["live"] = LiveSession(twin, live, say=lambda line: typer.echo(line, err=True))

        nav_opts = NavigationOptions(goals=tuple(goals), map_yaml=nav.get("map"), localisation=nav["localisation"],
                                     controller=nav["controller"], seed=opts.seed, timeout_s=duration_s)
        try:
            run = navigate(cfg, replace(options), nav_opts, static=static, on_twin=on_twin,
                           publish=recording or live is not None, drive=live is None)
        except KeyboardInterrupt:
            fail(f"interrupted at t={held['twin'].t_s:.2f} s simulated; no output written", code=130)
        finally:
            if "live" in held:
                held["live"].close()
        with all_or_nothing():
            if recording:
                from amr_twin.recording.rerun_log import record_run
                record_run(held["twin"], rrd_path=opts.record, mcap_path=opts.mcap)
            if opts.csv is not None:
                from amr_twin.recording.atomic_file import write_text
                from amr_twin.recording.run_report import csv_text
                write_text(opts.csv, csv_text(held["twin"].recorder.series()))
        twin = held["twin"]  # each fault with its effect, as run linear reports it
        return run, twin.faults.report(twin.recorder.series()) if twin.faults is not None else []

    run, fault_report = _guard(work)
    _report(run, opts.as_json, fault_report)
    if run.collisions:
        typer.echo(f"warning: {len(run.collisions)} collision(s), the first at t = {run.collisions[0]['t_s']:.2f} s "
                   f"with {run.collisions[0].get('world', '?')}", err=True)
    failed = [o for o in run.outcomes if o.status != "succeeded"]
    if failed:
        typer.echo(f"error: {failed[0].reason}", err=True)
        raise typer.Exit(EXIT_NOT_REACHED)


def _finite(value):
    """``value`` with every NaN or infinity (a goal with no plan: ``plan_length_m``) made None (JSON null)."""
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    if isinstance(value, dict):
        return {k: _finite(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_finite(v) for v in value]
    return value


def _report(run, as_json: bool, faults: list = ()) -> None:
    """Each goal's outcome, the faults with their effects, the distance and final pose; ``--json``: one
    object, in which a number that is not finite is null (JSON has no NaN)."""
    import numpy as np

    from amr_twin.recording.run_report import fault_lines

    goals = [{"goal": [o.goal[0], o.goal[1], None if o.goal[2] is None else math.degrees(o.goal[2])],
              "status": o.status, "reason": o.reason, "t_start_s": o.t_start_s, "t_end_s": o.t_end_s,
              "plan_length_m": o.first_plan_length_m, "recoveries": [list(r) for r in o.recoveries]}
             for o in run.outcomes]
    xy = run.pose_true[:, :2]
    info = {"goals": goals, "travelled_m": float(np.hypot(*np.diff(xy, axis=0).T).sum()),
            "final_pose": [float(v) for v in run.pose_true[-1]], "collisions": run.collisions,
            "collision_monitor": run.monitor_actions, "faults": list(faults), "sim_s": run.sim_s,
            "wall_s": run.wall_s}
    info = _finite(info)
    if as_json:
        numpy_scalar = lambda v: v.item() if isinstance(v, np.generic) else v  # noqa: E731
        typer.echo(json.dumps(info, allow_nan=False, default=numpy_scalar))
        return
    for i, g in enumerate(info["goals"]):
        where = f"goal {i + 1} ({g['goal'][0]:g}, {g['goal'][1]:g})"
        plan = "no plan" if g["plan_length_m"] is None else f"plan {g['plan_length_m']:.1f} m"
        if g["status"] == "succeeded":
            typer.echo(f"{where}: reached at t = {g['t_end_s']:.1f} s ({plan}, "
                       f"{len(g['recoveries'])} recoveries)")
        else:
            typer.echo(f"{where}: NOT reached: {g['reason']}")
    for line in fault_lines(info["faults"]):
        typer.echo(line)
    typer.echo(f"travelled {info['travelled_m']:.1f} m in {run.sim_s:.1f} simulated s ({run.wall_s:.1f} s wall); "
               f"final pose x {info['final_pose'][0]:.2f} m, y {info['final_pose'][1]:.2f} m, "
               f"yaw {math.degrees(info['final_pose'][2]):.0f} deg")


@shared(fail)
def goto(opts: RunOptions, ctx: typer.Context,
         goal: Optional[str] = typer.Option(None, "--goal", help="X_M,Y_M[,YAW_DEG] in the map frame (REP-103)."),
         map_: Optional[Path] = typer.Option(None, "--map", help="A map_server YAML (a map the fusion experiment "
                                             "saved, an imported ROS map); default: the world's true map."),
         localisation: str = typer.Option("ekf", "--localisation", help="truth (the twin's ground truth), ekf "
                                          "(odometry + gyro + UWB) or odom (wheel odometry alone)."),
         controller: str = typer.Option("mppi", "--controller", help="mppi or rpp (regulated pure pursuit).")
         ) -> None:
    """Navigate to a goal: plan on the map, follow, avoid, recover (amr_twin/navigation/, docs/navigation.md)."""
    if goal is None:
        fail("--goal is required (X_M,Y_M or X_M,Y_M,YAW_DEG)")
    if not any(_given(c, "firmware") for c in (ctx, ctx.parent)):
        opts.firmware = "improved"  # the faithful one restarts its ramps on every cmd_vel (docs/navigation.md)
    nav = {"map": None if map_ is None else str(map_), "localisation": localisation, "controller": controller}
    run_goals(opts, [parse_goal(goal)], nav, opts.duration_s)
