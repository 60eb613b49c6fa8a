"""What the faithful and the improved firmware do under each fault (``amr-twin experiment faults``).

Scenario (:data:`SCENARIO`): in the empty world, ``linear 0.5 m/s`` at t = 0
(38.2 RPM per wheel), a ``stop`` sent at :data:`STOP_T_S`, the run ending at
:data:`DURATION_S`; each fault of :data:`CASES` is injected at :data:`FAULT_T_S`,
when both firmwares have settled. Every case runs with both firmwares, against a
fault-free baseline of the same firmware. :func:`measure` reduces each run to the
numbers of the report (:mod:`amr_twin.experiments.faults.report`): wheel speeds
before the fault, during it and before the stop, the published samples, how far
the robot ended from the baseline and whether it stopped.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from amr_twin.model.config import TwinConfig
from amr_twin.assembly.twin import TwinOptions
from amr_twin.assembly.command import Command
from amr_twin.recording.run import run_mission

SPEED_M_S = 0.5
REFERENCE_RPM = 38.197  # linear 0.5 m/s: 0.5 / (2 pi 0.125) * 60
FAULT_T_S = 5.0
STOP_T_S = 9.0
DURATION_S = 12.0
WINDOW_S = 0.5
SCENARIO = (
    f"empty world, linear {SPEED_M_S} m/s at 0 s (38.2 RPM per wheel), stop sent at {STOP_T_S:g} "
    f"s, "
    f"run of {DURATION_S:g} s, fault at {FAULT_T_S:g} s"
)

CASES = (
    "hall-left-dead@5",
    "hall-left-dead@5:a",
    "hall-left-chatter@5:200",
    "motor-left-stall@5:for=2",
    "wheel-left-lifted@5:for=2",
    "rosserial-loss@5",
    "rosserial-loss@5:0.3",
    "rosserial-latency@5:250",
    "lidar-dead@5",
    "imu-stuck@5",
    "battery-sag@5:12",
    "battery-cut@5:for=2",
    "estop@5:for=2",
)
"""The faults studied, one of each kind (KIND@T[:ARGS], amr_twin/sim/faults.py)."""

FIRMWARES = ("faithful", "improved")


@dataclass(frozen=True)
class Case:
    """One simulation of the study: a fault (None: the baseline) under a firmware."""

    fault: str | None
    firmware: str
    cfg: TwinConfig
    seed: int = 0


def simulate(case: Case) -> dict:
    """Run one case; its series and fault report as plain arrays (picklable, for worker
    processes)."""
    from amr_twin.sim.faults import KINDS, parse_faults

    faults = parse_faults([case.fault]) if case.fault else ()
    sensors = any(KINDS[f.kind].needs_sensors for f in faults)
    options = TwinOptions(
        firmware=case.firmware,
        world="empty",
        seed=case.seed,
        sensors=("imu", "lidar") if sensors else (),
        faults=faults,
    )
    steps = [(0.0, Command("linear", speed_m_s=SPEED_M_S)), (STOP_T_S, Command("stop"))]
    result = run_mission(case.cfg, steps, DURATION_S, options)
    s = result.series
    return {
        "fault": case.fault,
        "firmware": case.firmware,
        "t_s": s.t_s,
        "true_rpm": s.true_rpm,
        "published": s.published,
        "pose": s.pose,
        "pwm_counts": s.pwm_counts,
        "mode": s.mode,
        "battery_v": s.battery_v,
        "commands": s.commands,
        "report": result.faults,
        "collisions": result.collisions,
        "wall_s": result.wall_s,
    }


def _mean(t: np.ndarray, values: np.ndarray, t0: float, t1: float) -> float:
    sel = (t >= t0) & (t < t1)
    return float(np.mean(values[sel])) if sel.any() else math.nan


def _path_m(pose: np.ndarray, sel: np.ndarray) -> float:
    xy = pose[sel, :2]
    return float(np.sum(np.hypot(*np.diff(xy, axis=0).T))) if len(xy) > 1 else 0.0


def measure(raw: dict, baseline: dict) -> dict:
    """The report's numbers for one run against its firmware's baseline (RPM, m, deg, counts)."""
    t, rpm, pose = raw["t_s"], raw["true_rpm"], raw["pose"]
    report = raw["report"][0] if raw["report"] else {}
    until = report.get("until_s") or STOP_T_S
    end_fault = min(until, STOP_T_S)
    wheels = {}
    for w, name in enumerate(("left", "right")):
        pub = raw["published"][w]
        after = pub[(pub[:, 0] >= FAULT_T_S) & (pub[:, 0] < STOP_T_S)] if len(pub) else pub
        wheels[name] = {
            "true_before_rpm": _mean(t, rpm[:, w], FAULT_T_S - WINDOW_S, FAULT_T_S),
            "true_during_rpm": _mean(t, rpm[:, w], end_fault - WINDOW_S, end_fault),
            "true_before_stop_rpm": _mean(t, rpm[:, w], STOP_T_S - WINDOW_S, STOP_T_S),
            "true_peak_rpm": float(np.max(np.abs(rpm[t >= FAULT_T_S, w]))),
            "true_end_rpm": float(rpm[-1, w]),
            "published_during": int(len(after)),
            "published_last_rpm": float(after[-1, 1]) if len(after) else None,
            "pwm_before_stop": int(raw["pwm_counts"][np.searchsorted(t, STOP_T_S) - 1, w]),
        }
    base_pose = baseline["pose"]
    n = min(len(pose), len(base_pose))
    dxy = float(np.hypot(*(pose[n - 1, :2] - base_pose[n - 1, :2])))
    dyaw = math.degrees(math.remainder(float(pose[n - 1, 2] - base_pose[n - 1, 2]), 2 * math.pi))
    moving_end = bool(np.any(np.abs(rpm[-1]) > 1.0))
    effect = report.get("effect", {})
    return {
        "fault": raw["fault"],
        "firmware": raw["firmware"],
        "wheels": wheels,
        "end_offset_m": dxy,
        "end_heading_offset_deg": dyaw,
        "moved_after_stop_m": _path_m(pose, t >= STOP_T_S + 0.5),
        "baseline_moved_after_stop_m": _path_m(base_pose, baseline["t_s"] >= STOP_T_S + 0.5),
        "stopped_at_end": not moving_end,
        "min_battery_v": float(np.min(raw["battery_v"][t >= FAULT_T_S])),
        "scan_published_after": effect.get("scan_published_after"),
        "imu_published_after": effect.get("imu/data_raw_published_after"),
        "imu_distinct_after": effect.get("imu/data_raw_distinct_values_after"),
        "collisions": len(raw["collisions"]),
    }


def run(
    cfg: TwinConfig, jobs: int = 1, progress: bool = True, cases: tuple[str, ...] = CASES
) -> dict:
    """Simulate every case under both firmwares and the baselines; return raw runs and measures."""
    import time

    from amr_twin.experiments.runner.executor import run_all

    wall0 = time.perf_counter()
    todo = [Case(None, fw, cfg) for fw in FIRMWARES] + [
        Case(c, fw, cfg) for c in cases for fw in FIRMWARES
    ]
    raw = {
        (item.fault, item.firmware): out
        for item, out in run_all(simulate, todo, jobs, "fault runs", progress)
    }
    rows = [measure(raw[(c, fw)], raw[(None, fw)]) for c in cases for fw in FIRMWARES]
    return {
        "scenario": SCENARIO,
        "cases": list(cases),
        "rows": rows,
        "raw": raw,
        "wall_s": time.perf_counter() - wall0,
    }
