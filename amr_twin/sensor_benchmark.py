"""Cost of the IMU and the LiDAR: the twin with its sensors against bare physics.

Scenario: the twin benchmark's (chapter 5 run 3: linear 0.7 m/s, faithful
firmware, warehouse) with ``TwinOptions(sensors=True)``: IMU at 100 Hz and
RPLIDAR A1 at 5.5 Hz (2000 samples/s, poses sampled on the 10 ms record grid,
beams cast in two calls per rotation, sensors/lidar.py). Wall-clock
figures are the best of a few repeats (the machine is shared and noisy).
"""

from __future__ import annotations

import time

import mujoco

from .bus import Bus
from .clock import VirtualClock
from .config import TwinConfig
from .loop import Twin
from .sensors.lidar import Lidar
from .twin_benchmark import twin_wall_s

REPEATS = 3
SCAN_REPEATS = 200


def lidar_scan_cost_us(twin: Twin) -> tuple[float, float]:
    """(one rotation as the twin casts it, the same beams in one call), us per scan.

    The first figure runs a LiDAR fed like the twin's (pose samples on the 10 ms
    grid, casts every ``loop_cast_us`` and at the end of the rotation, noise) on
    the twin's model and data, standing still, on a clock of its own; the second
    casts the 364 beams from the present pose in one ``mj_multiRay`` call.
    """
    m, d, cfg = twin.physics.model, twin.physics.data, twin.cfg.lidar
    clock = VirtualClock()
    lidar = Lidar(m, d, clock, Bus(clock), cfg, autostart=False)
    lidar.start_motor(grid_us=twin.grid_us, samplers=[])
    grid_us = twin.grid_us
    t_us, per_scan = 0, -(-lidar.scan_us // grid_us)
    now = time.perf_counter
    best_rotation = best_one = float("inf")
    for _ in range(SCAN_REPEATS):
        t0 = now()
        for _k in range(per_scan):
            lidar.on_sample(t_us)
            t_us += grid_us
        t1 = now()
        lidar.scan_now()
        t2 = now()
        best_rotation, best_one = min(best_rotation, t1 - t0), min(best_one, t2 - t1)
    return best_rotation * 1e6, best_one * 1e6


def sensor_figures(cfg: TwinConfig, sim_s: float, bare_physics_s_per_sim_s: float | None = None) -> dict:
    """Sensor cost figures.

    Parameters
    ----------
    cfg : TwinConfig
        Parameters (``imu:`` and ``lidar:`` sections included).
    sim_s : float
        Simulated duration of each timed run, s.
    bare_physics_s_per_sim_s : float, optional
        Wall seconds per simulated second of bare ``mj_step`` on the same scenario,
        measured earlier in the same run. The reference is the best of it and of
        this function's own bare repeats, interleaved with the twin's (the
        machine is noisy: a figure measured minutes apart is not comparable).

    Returns
    -------
    dict
        ``sensors_ratio`` (twin with sensors / bare physics), ``twin_no_sensors_ratio``
        (same twin without sensors / bare physics), ``sensors_s_per_sim_s``,
        ``lidar_scan_us`` (one rotation as the twin casts it: pose samples, casts,
        noise),
        ``lidar_scan_one_call_us`` (the same beams in one ``mj_multiRay``),
        ``lidar_beams_per_scan``.
    """
    with_best = without_best = float("inf")
    bare_best = float("inf") if bare_physics_s_per_sim_s is None else bare_physics_s_per_sim_s * sim_s
    twin = None
    for _ in range(REPEATS):  # interleaved so that a disturbance hits all three
        wall, twin = twin_wall_s(cfg, sim_s, sensors=True)
        with_best = min(with_best, wall)
        m, d = twin.physics.model, twin.physics.data
        nstep = int(round(sim_s / m.opt.timestep))
        t0 = time.perf_counter()
        mujoco.mj_step(m, d, nstep)
        bare_best = min(bare_best, time.perf_counter() - t0)
        without_best = min(without_best, twin_wall_s(cfg, sim_s, sensors=False)[0])
    mujoco.mj_forward(twin.physics.model, twin.physics.data)
    scan_groups_us, scan_one_us = lidar_scan_cost_us(twin)
    bare = bare_best / sim_s
    return {
        "sensors_s_per_sim_s": round(with_best / sim_s, 5),
        "sensors_ratio": round(with_best / sim_s / bare, 3),
        "twin_no_sensors_ratio": round(without_best / sim_s / bare, 3),
        "lidar_scan_us": round(scan_groups_us, 1),
        "lidar_scan_one_call_us": round(scan_one_us, 1),
        "lidar_beams_per_scan": twin.lidar.n_beams,
    }
