"""Cost of the IMU and the LiDAR: the twin with its sensors against bare physics.

Scenario: the twin benchmark's (chapter 5 run 3: linear 0.7 m/s, faithful
firmware, warehouse) with ``TwinOptions(sensors=True)``: IMU at 100 Hz and
RPLIDAR A1 at 5.5 Hz (2000 samples/s, beams cast in 4 ms groups). Wall-clock
figures are the best of a few repeats (the machine is shared and noisy).
"""

from __future__ import annotations

import time

import mujoco

from .config import TwinConfig
from .loop import Twin
from .twin_benchmark import twin_wall_s

REPEATS = 3
SCAN_REPEATS = 200


def lidar_scan_cost_us(twin: Twin) -> tuple[float, float]:
    """(one rotation cast in its clock-event groups, the same beams in one call), us per scan."""
    lidar = twin.lidar
    now = time.perf_counter
    best_groups = best_one = float("inf")
    for _ in range(SCAN_REPEATS):
        t0 = now()
        for a, b in lidar.groups:
            lidar.cast(a, b)
        lidar.noisy_ranges(lidar.dist_m, lidar.hit_geom)
        t1 = now()
        lidar.scan_now()
        t2 = now()
        best_groups, best_one = min(best_groups, t1 - t0), min(best_one, t2 - t1)
    return best_groups * 1e6, best_one * 1e6


def sensor_figures(cfg: TwinConfig, sim_s: float, bare_physics_s_per_sim_s: float) -> dict:
    """Sensor cost figures.

    Parameters
    ----------
    cfg : TwinConfig
        Parameters (``imu:`` and ``lidar:`` sections included).
    sim_s : float
        Simulated duration of each timed run, s.
    bare_physics_s_per_sim_s : float
        Wall seconds per simulated second of bare ``mj_step`` (the reference).

    Returns
    -------
    dict
        ``sensors_ratio`` (twin with sensors / bare physics), ``twin_no_sensors_ratio``
        (same twin without sensors / bare physics), ``sensors_s_per_sim_s``,
        ``lidar_scan_us`` (one rotation, cast in its groups, noise included),
        ``lidar_scan_one_call_us`` (the same beams in one ``mj_multiRay``),
        ``lidar_beams_per_scan``.
    """
    with_best = without_best = float("inf")
    twin = None
    for _ in range(REPEATS):  # interleaved so that a disturbance hits both
        wall, twin = twin_wall_s(cfg, sim_s, sensors=True)
        with_best = min(with_best, wall)
        without_best = min(without_best, twin_wall_s(cfg, sim_s, sensors=False)[0])
    mujoco.mj_forward(twin.physics.model, twin.physics.data)
    scan_groups_us, scan_one_us = lidar_scan_cost_us(twin)
    bare = bare_physics_s_per_sim_s
    return {
        "sensors_s_per_sim_s": round(with_best / sim_s, 5),
        "sensors_ratio": round(with_best / sim_s / bare, 3),
        "twin_no_sensors_ratio": round(without_best / sim_s / bare, 3),
        "lidar_scan_us": round(scan_groups_us, 1),
        "lidar_scan_one_call_us": round(scan_one_us, 1),
        "lidar_beams_per_scan": twin.lidar.n_beams,
    }
