"""``run goto``'s options: the run options whose default or meaning differs for goto, the goal's
numbers, and each goal checked against the map from where the robot will be
(:mod:`amr_twin.cli.goto`).
"""

from __future__ import annotations

import math
from pathlib import Path


from amr_twin.cli.common import _start_pose, fail
from amr_twin.navigation.registries import CONTROLLERS, LOCALISATIONS

GOTO_DEFAULTS = {"xy_tolerance_m": 0.25, "yaw_tolerance_deg": 14.3, "inflation_radius_m": 1.0}
"""The parameter file's navigation.navigator.xy_tolerance_m, yaw_tolerance_rad (0.25 rad) and
navigation.costmap.inflation_radius_m, as goto's help states them (a test holds them to the
file)."""
RUN_OVERRIDES = {
    "duration_s": {
        "help": "Time limit of the goals, simulated s after the 2 s rest (default: 60 s + 4 s "
        "per metre of "
        "the goals' first plans), at most 3600."
    },
    "firmware": {
        "default": "improved",
        "help": "Arduino firmware: improved, faithful or avr; default improved "
        "(the faithful one restarts its ramps on every cmd_vel: docs/explanation/navigation.md).",
    },
    "sensors": {"help": "Always on with goto: the LiDAR and IMU feed the navigation."},
    "seed": {
        "help": "Seed of the random draws: the sensors' noise, the MPPI's samples, --fault and "
        "--actors-random. "
        "Same seed, same run."
    },
    "live": {
        "help": "Serve the twin live while it runs, paced to --rate: foxglove (the default; "
        "publish a "
        "geometry_msgs/msg/PoseStamped on /goal_pose, frame map or odom, for a new goal) or rerun."
    },
    "rate": {
        "help": "With --live or --ros1: simulated seconds per wall second (default 1 with "
        "--live; --ros1 alone: "
        "0, as fast as possible)."
    },
    "ros1": {
        "help": "Join the ROS 1 graph at ROS_MASTER_URI (docs/how-to/ros1.md): the twin's "
        "topics, and the navigator as "
        "move_base (a goal of the action or on move_base_simple/goal preempts --goal)."
    },
    "serial_pty": {"help": "Not with goto (refused)."},
}
"""The run options whose default or meaning differs for goto
(:func:`amr_twin.cli.run_options.shared`)."""


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


def checked_goals(cfg, opts, goals, nav: dict):
    """The static map and the start pose, every goal checked against them (module docstring)."""
    import numpy as np

    from amr_twin.model.worlds import MapError, default_start
    from amr_twin.navigation.footprint import robot_footprint
    from amr_twin.navigation.planner import GlobalPlanner
    from amr_twin.navigation.stack import load_static_map, make_costmap

    for registry, key in ((LOCALISATIONS, "localisation"), (CONTROLLERS, "controller")):
        try:
            registry.get(nav[key])
        except ValueError as exc:
            fail(str(exc))
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
        fail(
            f"the start ({here[0]:g}, {here[1]:g}) lies outside the map of {of}: give --start "
            f"X_M,Y_M,YAW_DEG on it"
        )
    for x, y, yaw in goals:
        name = f"goal {x:g},{y:g}"
        if planner.plan(here, np.array([x, y])) is None:
            fail(f"{name}: {planner.last_error}")
        here = np.array([x, y])
    return static
