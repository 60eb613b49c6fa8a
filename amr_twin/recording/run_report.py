"""What ``amr-twin run`` prints and writes: the ``--json`` summary, the text lines, the ``--csv`` table."""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

if TYPE_CHECKING:  # numpy and the recorder (the model build) stay off the CLI's start-up path (--help)
    import numpy as np

    from amr_twin.recording.recorder import RunSeries

CSV_COLUMNS = ("t_s", "ref_rpm_left", "ref_rpm_right", "pub_rpm_left", "pub_rpm_right",
               "true_rpm_left", "true_rpm_right", "pwm_counts_left", "pwm_counts_right",
               "x_m", "y_m", "yaw_rad", "odom_x_m", "odom_y_m", "odom_yaw_rad",
               "current_a_left", "current_a_right", "battery_a", "battery_v")
"""Columns of ``--csv``: reference RPM (motion x speed of wheel_Command), published RPM
(|wheelN_Vel| x the wheel's commanded direction, held between samples, 0 before the
first), true RPM, analogWrite counts, true pose (world) and odometry pose (odom frame,
held), each motor's (phase) current (+ driving forward), the battery's current and
voltage. Every RPM, here and in ``--json``, is signed: + = the wheel rolls forward."""
CSV_COMMENT = ("# amr-twin run: every rpm column is signed, + = the wheel rolls forward (REP-103); ref_rpm = "
               "motion x speed of wheel_Command, pub_rpm = |wheelN_Vel| x the commanded direction; "
               "x_m, y_m, yaw_rad in the world, odom_* in odom; current_a + driving forward")
"""First line of ``--csv``: ``pandas.read_csv(path, comment="#")``, ``numpy.genfromtxt(path, delimiter=",",
names=True, skip_header=1)``."""


def _held(t_query: np.ndarray, t_sample: np.ndarray, values: np.ndarray, before: float = 0.0) -> np.ndarray:
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
    return np.column_stack([t, *ref, *pub, series.true_rpm, series.pwm_counts, series.pose, *odom,
                            series.current_a, series.battery_a, series.battery_v])


def csv_text(series: RunSeries) -> str:
    """The ``--csv`` file: a header of :data:`CSV_COLUMNS`, one row per 10 ms."""
    rows = series_table(series)
    lines = [CSV_COMMENT, ",".join(CSV_COLUMNS)]
    lines += [",".join(f"{v:.9g}" for v in row) for row in rows]
    return "\n".join(lines) + "\n"


def json_ready(value):
    """``value`` with every non-finite float (NaN, inf) replaced by None, recursively (strict JSON)."""
    if isinstance(value, float) and not math.isfinite(value):
        return None
    if isinstance(value, dict):
        return {k: json_ready(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [json_ready(v) for v in value]
    return value


def _step_metrics(series: RunSeries, wheel: int, reference_rpm: float) -> dict:
    """Step metrics of a wheel's signed published speed (those of
    :data:`amr_twin.analysis.metrics.SIGNED_METRICS` signed)."""
    from amr_twin.analysis.metrics import step_info
    from amr_twin.recording.recorder import signed_published

    pub = signed_published(series, wheel)
    if reference_rpm == 0.0 or len(pub) < 2:
        return {}
    return step_info(pub[:, 0], pub[:, 1], reference_rpm).as_dict(sign=1.0 if reference_rpm > 0 else -1.0)


def summary(result, single: bool, start_xy_yaw=None) -> dict:
    """The ``--json`` object of a run.

    ``collisions``: every contact episode of the robot's body with the world
    (:meth:`amr_twin.sim.collisions.Collision.as_dict`); ``stopped_by_collision``: the run
    ended at the first one (``--stop-on-collision``); ``faults``: each injected fault
    with its effect (:meth:`amr_twin.sim.fault_injector.FaultInjector.report`).
    """
    import numpy as np

    series, wc = result.series, result.wheel_command
    code = next((c for c in result.codes if c != 0), 0)
    last_s = series.t_s >= series.t_s[-1] - 1.0  # "final" electrical values: the last second
    wheels = {}
    from amr_twin.recording.recorder import signed_published

    for w, name in enumerate(("left", "right")):
        reference = wc[2 * w] * wc[2 * w + 1] if wc else 0.0  # signed: motion x speed
        pub = signed_published(series, w)
        entry = {"motion": int(wc[2 * w]) if wc else 0, "reference_rpm": reference,
                 "final_rpm": float(pub[-1, 1]) if len(pub) else 0.0,
                 "final_rpm_t_s": float(pub[-1, 0]) if len(pub) else None,
                 "true_final_rpm": float(series.true_rpm[-1, w]), "samples": int(len(pub)),
                 "current_a_final": float(series.current_a[last_s, w].mean()),
                 "current_a_peak": float(np.abs(series.current_a[:, w]).max())}
        if single:
            entry.update(_step_metrics(series, w, reference))
        wheels[name] = entry
    commands = [dict(c.describe(), t_s=t) for t, c in result.commands]
    x, y, yaw = (float(v) for v in series.pose[-1])
    odom = series.odom[-1, 1:] if len(series.odom) else np.zeros(3)
    out = {
        "command": (commands[0] if commands else None) if single else commands, "wheel_command": wc,
        "code": code, "codes": result.codes, "errors": result.errors, "wheels": wheels,
        "final_pose": {"x_m": x, "y_m": y, "yaw_rad": yaw},
        "final_odom_pose": {"x_m": float(odom[0]), "y_m": float(odom[1]), "yaw_rad": float(odom[2])},
        "battery": _battery_summary(series),
        "collisions": result.collisions, "stopped_by_collision": result.halted,
        "faults": result.faults, "sim_s": result.sim_s, "wall_s": result.wall_s}
    if start_xy_yaw is not None:
        sx, sy, syaw = start_xy_yaw
        out["start_pose"] = {"x_m": sx, "y_m": sy, "yaw_rad": syaw}
        turned = math.remainder(yaw - syaw, math.tau)
        out["from_start"] = {"distance_m": math.hypot(x - sx, y - sy), "heading_deg": math.degrees(turned)}
    return json_ready(out)


def _battery_summary(series: RunSeries) -> dict:
    """The pack over the run: mean current, final voltage, energy drawn and per metre driven."""
    import numpy as np

    power = series.battery_v * series.battery_a
    energy = float(np.sum(0.5 * (power[1:] + power[:-1]) * np.diff(series.t_s)))
    distance = float(np.sum(np.hypot(*np.diff(series.pose[:, :2], axis=0).T)))
    return {"battery_a_mean": float(series.battery_a.mean()), "battery_v_final": float(series.battery_v[-1]),
            "energy_j": energy, "distance_m": distance,
            "energy_j_per_m": energy / distance if distance > 0.05 else None}


def text_lines(result, info: dict) -> list[str]:
    """The plain-text report of a run (stdout without ``--json``)."""
    lines = []
    wc = result.wheel_command
    if wc:
        lines.append(f"wheel_Command [{wc[0]:g}, {wc[1]:.5f}, {wc[2]:g}, {wc[3]:.5f}]")
    for name, entry in info["wheels"].items():
        lines.append(f"{name:5s} reference {entry['reference_rpm']:8.3f} RPM, true {entry['true_final_rpm']:8.3f} RPM, "
                     + _published(entry, result.sim_s))
    for fault in info["faults"]:
        until = f" until {fault['until_s']:g} s" if fault["until_s"] is not None else ""
        lines.append(f"fault {fault['kind']} at {fault['t_s']:g} s{until}: " + _fault_effect(fault))
    for c in info["collisions"]:
        lines.append(_collision_line(c))
    if not info["collisions"]:
        lines.append("no collision")
    pose = info["final_pose"]
    lines.append(f"pose x {pose['x_m']:.3f} m, y {pose['y_m']:.3f} m, yaw {pose['yaw_rad']:.3f} rad "
                 f"after {result.sim_s:g} s simulated ({result.wall_s:.2f} s wall)"
                 + (", stopped by the collision" if result.halted else ""))
    moved = info.get("from_start")
    if moved is not None and len(result.commands) > 1:  # a mission: where it ended against where it began
        lines.append(f"ended {moved['distance_m']:.2f} m from its start pose, heading {moved['heading_deg']:+.1f} deg "
                     "from its start heading (a mission's commands are timed: nothing steers by the pose)")
    return lines


def _published(entry: dict, end_s: float) -> str:
    """The last published speed with its time: the firmware publishes once per wheel
    revolution and nothing while the wheel stands, so the last sample may be old."""
    t = entry.get("final_rpm_t_s")
    if t is None:
        return "nothing published"
    text = f"last published {entry['final_rpm']:8.3f} RPM at {t:.2f} s"
    if abs(entry["true_final_rpm"]) < 0.5 and entry["final_rpm"] != 0.0:
        text += f", {end_s - t:.2f} s before the end (the wheel stands: nothing is published at rest)"
    return text


def _fault_effect(fault: dict) -> str:
    wheels = fault["effect"]["wheels"]
    parts = []
    for name, w in wheels.items():
        parts.append(f"{name} true {w['true_rpm_before'] if w['true_rpm_before'] is not None else float('nan'):.1f} -> "
                     f"{w['true_rpm_end'] if w['true_rpm_end'] is not None else float('nan'):.1f} RPM, "
                     f"{w['published_after']} published after")
    return "; ".join(parts) + f"; moved {fault['effect']['moved_after_m']:.2f} m after"


def _collision_line(c: dict) -> str:
    pose = c["robot_pose"]
    return (f"collision at t = {c['t_s']:.2f} s: {', '.join(c['robot_parts'])} hit {c['hit']} at "
            f"({c['x_m']:.2f}, {c['y_m']:.2f}) m, robot at ({pose['x_m']:.2f}, {pose['y_m']:.2f}) m; "
            f"in contact until {c['until_s']:.2f} s, peak force {c['peak_force_n']:.0f} N")


def collision_warning(info: dict) -> str | None:
    """One stderr line when the run had collisions (also with ``--json``)."""
    hits = info["collisions"]
    if not hits:
        return None
    first = hits[0]
    more = f" and {len(hits) - 1} more" if len(hits) > 1 else ""
    return (f"warning: collision at t = {first['t_s']:.2f} s with {first['hit']} at "
            f"({first['x_m']:.2f}, {first['y_m']:.2f}) m{more}" + (" (run stopped)" if info["stopped_by_collision"]
                                                                  else ""))
