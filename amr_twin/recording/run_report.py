"""What ``amr-twin run`` prints and writes: the text lines, the ``--csv`` table (the ``--json``
summary:
:mod:`amr_twin.recording.run_summary`)."""

from __future__ import annotations

from typing import TYPE_CHECKING

if (
    TYPE_CHECKING
):  # numpy and the recorder (the model build) stay off the CLI's start-up path (--help)
    import numpy as np

    from amr_twin.recording.recorder import RunSeries
    from amr_twin.recording.run_summary import RunSummary, WheelSummary

CSV_COLUMNS = (
    "t_s",
    "ref_rpm_left",
    "ref_rpm_right",
    "pub_rpm_left",
    "pub_rpm_right",
    "true_rpm_left",
    "true_rpm_right",
    "pwm_counts_left",
    "pwm_counts_right",
    "x_m",
    "y_m",
    "yaw_rad",
    "odom_x_m",
    "odom_y_m",
    "odom_yaw_rad",
    "current_a_left",
    "current_a_right",
    "battery_a",
    "battery_v",
)
"""Columns of ``--csv``: reference RPM (motion x speed of wheel_Command), published RPM
(|wheelN_Vel| x the wheel's commanded direction, held between samples, 0 before the
first), true RPM, analogWrite counts, true pose (world) and odometry pose (odom frame,
held), each motor's (phase) current (+ driving forward), the battery's current and
voltage. Every RPM, here and in ``--json``, is signed: + = the wheel rolls forward."""
CSV_COMMENT = (
    "# amr-twin run: every rpm column is signed, + = the wheel rolls forward (REP-103); ref_rpm = "
    "motion x speed of wheel_Command, pub_rpm = |wheelN_Vel| x the commanded direction; "
    "x_m, y_m, yaw_rad in the world, odom_* in odom; current_a + driving forward"
)
"""First line of ``--csv``: ``pandas.read_csv(path, comment="#")``, ``numpy.genfromtxt(path,
delimiter=",", names=True, skip_header=1)``."""


def _held(
    t_query: np.ndarray, t_sample: np.ndarray, values: np.ndarray, before: float = 0.0
) -> np.ndarray:
    """Zero-order hold of samples (t_sample, values) at ``t_query``."""
    import numpy as np

    idx = np.searchsorted(t_sample, t_query, side="right") - 1
    out = np.where(idx >= 0, values[np.clip(idx, 0, None)] if len(values) else before, before)
    return out.astype(float)


def series_table(series: RunSeries) -> np.ndarray:
    """The ``--csv`` table, shape (n, len(CSV_COLUMNS))."""
    import numpy as np

    from amr_twin.recording.recorder import signed_published

    t = series.t_s
    cmd_t = np.array([c[0] for c in series.commands], float)
    cmd = np.array([c[1] for c in series.commands], float).reshape(-1, 4)
    ref = [_held(t, cmd_t, cmd[:, 0] * cmd[:, 1]), _held(t, cmd_t, cmd[:, 2] * cmd[:, 3])]
    pub = [_held(t, p[:, 0], p[:, 1]) for p in (signed_published(series, w) for w in (0, 1))]
    odom = [_held(t, series.odom[:, 0], series.odom[:, k]) for k in (1, 2, 3)]
    return np.column_stack(
        [
            t,
            *ref,
            *pub,
            series.true_rpm,
            series.pwm_counts,
            series.pose,
            *odom,
            series.current_a,
            series.battery_a,
            series.battery_v,
        ]
    )


def csv_text(series: RunSeries) -> str:
    """The ``--csv`` file: a header of :data:`CSV_COLUMNS`, one row per 10 ms."""
    rows = series_table(series)
    lines = [CSV_COMMENT, ",".join(CSV_COLUMNS)]
    lines += [",".join(f"{v:.9g}" for v in row) for row in rows]
    return "\n".join(lines) + "\n"


def text_lines(result, info: RunSummary) -> list[str]:
    """The plain-text report of a run (stdout without ``--json``)."""
    lines = []
    wc = result.wheel_command
    if wc:
        lines.append(f"wheel_Command [{wc[0]:g}, {wc[1]:.5f}, {wc[2]:g}, {wc[3]:.5f}]")
    for name, entry in info.wheels.items():
        lines.append(
            f"{name:5s} reference {entry.reference_rpm:8.3f} RPM, true "
            f"{entry.true_final_rpm:8.3f} RPM, " + _published(entry, result.sim_s)
        )
    lines.extend(fault_lines(info.faults))
    for c in info.collisions:
        lines.append(_collision_line(c))
    if not info.collisions:
        lines.append("no collision")
    pose = info.final_pose
    lines.append(
        f"pose x {pose.x_m:.3f} m, y {pose.y_m:.3f} m, yaw {pose.yaw_rad:.3f} rad "
        f"after {result.sim_s:g} s simulated ({result.wall_s:.2f} s wall)"
        + (", stopped by the collision" if result.halted else "")
    )
    step = info.tyre_timestep
    if step is not None:
        lines.append(
            f"physics timestep {step['timestep_s'] * 1e3:g} ms instead of "
            f"{step['configured_timestep_s'] * 1e3:g} "
            f"ms: the tyres' stability number {max(step['stability_number_configured']):.2f} "
            f"exceeded "
            f"{step['stability_limit']:g} (docs/explanation/tyres.md)"
        )
    moved = info.from_start
    if (
        moved is not None and len(result.commands) > 1
    ):  # a mission: where it ended against where it began
        lines.append(
            f"ended {moved.distance_m:.2f} m from its start pose, heading "
            f"{moved.heading_deg:+.1f} deg "
            "from its start heading (a mission's commands are timed: nothing steers by the pose)"
        )
    return lines


def _published(entry: WheelSummary, end_s: float) -> str:
    """The last published speed with its time: the firmware publishes once per wheel
    revolution and nothing while the wheel stands, so the last sample may be old."""
    t = entry.final_rpm_t_s
    if t is None:
        return "nothing published"
    text = f"last published {entry.final_rpm:8.3f} RPM at {t:.2f} s"
    if abs(entry.true_final_rpm) < 0.5 and entry.final_rpm != 0.0:
        text += (
            f", {end_s - t:.2f} s before the end (the wheel stands: nothing is published at rest)"
        )
    return text


def fault_lines(faults: list[dict]) -> list[str]:
    """One line per injected fault and its effect
    (:meth:`~amr_twin.sim.fault_injector.FaultInjector.report`)."""
    lines = []
    for fault in faults:
        until = f" until {fault['until_s']:g} s" if fault["until_s"] is not None else ""
        lines.append(f"fault {fault['kind']} at {fault['t_s']:g} s{until}: " + _fault_effect(fault))
    return lines


def _fault_effect(fault: dict) -> str:
    wheels = fault["effect"]["wheels"]
    parts = []
    for name, w in wheels.items():
        parts.append(
            f"{name} true "
            f"{w['true_rpm_before'] if w['true_rpm_before'] is not None else float('nan'):.1f} "
            f"-> "
            f"{w['true_rpm_end'] if w['true_rpm_end'] is not None else float('nan'):.1f} RPM, "
            f"{w['published_after']} published after"
        )
    sensors = "".join(
        f"; {fault['effect'][f'{topic}_published_after']} {topic} published after"
        for topic in ("scan", "imu/data_raw")
        if f"{topic}_published_after" in fault["effect"]
    )
    return "; ".join(parts) + f"; moved {fault['effect']['moved_after_m']:.2f} m after" + sensors


def _collision_line(c: dict) -> str:
    pose = c["robot_pose"]
    return (
        f"collision at t = {c['t_s']:.2f} s: {', '.join(c['robot_parts'])} hit {c['hit']} at "
        f"({c['x_m']:.2f}, {c['y_m']:.2f}) m, robot at ({pose['x_m']:.2f}, {pose['y_m']:.2f}) m; "
        f"in contact until {c['until_s']:.2f} s, peak force {c['peak_force_n']:.0f} N"
    )


def collision_warning(info: RunSummary) -> str | None:
    """One stderr line when the run had collisions (also with ``--json``)."""
    hits = info.collisions
    if not hits:
        return None
    first = hits[0]
    more = f" and {len(hits) - 1} more" if len(hits) > 1 else ""
    return (
        f"warning: collision at t = {first['t_s']:.2f} s with {first['hit']} at "
        f"({first['x_m']:.2f}, {first['y_m']:.2f}) m{more}"
        + (" (run stopped)" if info.stopped_by_collision else "")
    )
