"""What ``run goto`` prints: each goal's outcome with the truth's and the estimate's final error,
the least clearance to the world's obstacles, the faults; ``--json``: one object, never a NaN (JSON
has none)."""

from __future__ import annotations

import json
import math

import typer


def clearance(cfg, world: str, run) -> tuple[float | None, float | None]:
    """The least clearance of the true footprint to the world's obstacles over the run (10 Hz), m,
    and its time, s; ``(None, None)`` in a world without any."""
    import numpy as np

    from amr_twin.experiments.navigation.metrics import footprint_clearance_m, world_obstacle_boxes
    from amr_twin.navigation.footprint import robot_footprint

    clearance = footprint_clearance_m(
        run.pose_true[::10], robot_footprint(cfg), world_obstacle_boxes(cfg, world)
    )
    if not len(clearance) or not np.isfinite(clearance).any():
        return None, None
    k = int(np.argmin(clearance))
    return float(clearance[k]), float(run.t_s[::10][k])


def _finite(value):
    """``value`` with every NaN or infinity (a goal with no plan: ``plan_length_m``) made None (JSON
    null)."""
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    if isinstance(value, dict):
        return {k: _finite(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_finite(v) for v in value]
    return value


def report(run, as_json: bool, faults: list = (), clearance: tuple = (None, None)) -> None:
    """Each goal's outcome with the truth's and the estimate's final error, the faults with their
    effects, the distance, the least clearance and the final pose; ``--json``: one object, in which
    a number that is not finite is null (JSON has no NaN)."""
    import numpy as np

    from amr_twin.recording.run_report import fault_lines

    goals = [
        {
            "goal": [o.goal[0], o.goal[1], None if o.goal[2] is None else math.degrees(o.goal[2])],
            "status": o.status,
            "reason": o.reason,
            "t_start_s": o.t_start_s,
            "t_end_s": o.t_end_s,
            "plan_length_m": o.first_plan_length_m,
            "recoveries": [list(r) for r in o.recoveries],
            "final_error": e.as_json(),
        }
        for o, e in zip(run.outcomes, run.final_errors)
    ]
    xy = run.pose_true[:, :2]
    info = {
        "goals": goals,
        "travelled_m": float(np.hypot(*np.diff(xy, axis=0).T).sum()),
        "final_pose": [float(v) for v in run.pose_true[-1]],
        "min_clearance_m": clearance[0],
        "min_clearance_t_s": clearance[1],
        "collisions": run.collisions,
        "collision_monitor": run.monitor_actions,
        "faults": list(faults),
        "sim_s": run.sim_s,
        "wall_s": run.wall_s,
    }
    info = _finite(info)
    if as_json:
        numpy_scalar = lambda v: v.item() if isinstance(v, np.generic) else v  # noqa: E731
        typer.echo(json.dumps(info, allow_nan=False, default=numpy_scalar))
        return
    for i, g in enumerate(info["goals"]):
        where = f"goal {i + 1} ({g['goal'][0]:g}, {g['goal'][1]:g})"
        plan = "no plan" if g["plan_length_m"] is None else f"plan {g['plan_length_m']:.1f} m"
        if g["status"] == "succeeded":
            typer.echo(
                f"{where}: reached at t = {g['t_end_s']:.1f} s ({plan}, "
                f"{len(g['recoveries'])} recoveries); {_errors_text(g['final_error'])}"
            )
        else:
            typer.echo(
                f"{where}: NOT reached ({g['status']}): {g['reason']}; "
                f"{_errors_text(g['final_error'])}"
            )
    for line in fault_lines(info["faults"]):
        typer.echo(line)
    least = (
        ""
        if clearance[0] is None
        else f"; least clearance {clearance[0]:.2f} m at t = {clearance[1]:.1f} s"
    )
    typer.echo(
        f"travelled {info['travelled_m']:.1f} m in {run.sim_s:.1f} simulated s ({run.wall_s:.1f} "
        f"s wall){least}; "
        f"final pose x {info['final_pose'][0]:.2f} m, y {info['final_pose'][1]:.2f} m, "
        f"yaw {math.degrees(info['final_pose'][2]):.0f} deg"
    )


def _errors_text(e: dict) -> str:
    """``true pose 0.12 m, 3 deg from the goal (estimate 0.10 m, 2 deg)``."""

    def one(xy, yaw):
        return "-" if xy is None else f"{xy:.2f} m" + ("" if yaw is None else f", {yaw:.0f} deg")

    return (
        f"true pose {one(e['true_xy_m'], e['true_yaw_deg'])} from the goal "
        f"(estimate {one(e['estimate_xy_m'], e['estimate_yaw_deg'])})"
    )
