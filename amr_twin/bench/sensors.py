"""Cost of the IMU and the LiDAR: the twin with its sensors against bare physics.

Scenario: the twin benchmark's (chapter 5 run 3: linear 0.7 m/s, faithful
firmware, warehouse aisle, :data:`~amr_twin.bench.twin.BENCH_START`) with ``TwinOptions(sensors=True)``: IMU at 100 Hz and
RPLIDAR A1 at 5.5 Hz (2000 samples/s, laser pose sampled every 20 ms on the
record grid, the 364 beams of a rotation cast in one call, sensors/lidar.py).
Figures: CPU time, medians of interleaved repeats (amr_twin/bench/physics.py).
"""

from __future__ import annotations

import statistics


from amr_twin.bench.physics import REPEATS, bare_steps_s, paired_ratio, timer
from amr_twin.ros.bus import Bus
from amr_twin.base.clock import VirtualClock
from amr_twin.model.config import TwinConfig
from amr_twin.sim.loop import Twin
from amr_twin.sensors.lidar import Lidar
from amr_twin.bench.twin import twin_run_s

SCAN_REPEATS = 200


def lidar_scan_cost_us(twin: Twin) -> tuple[float, float]:
    """(one rotation as the twin casts it, the same beams in one call), us per scan.

    The first figure runs a LiDAR fed like the twin's (pose samples every 20 ms
    on the record grid, one cast at the end of the rotation, noise) on
    the twin's model and data, standing still, on a clock of its own; the second
    casts the 364 beams from the present pose in one ``mj_multiRay`` call.
    """
    cfg = twin.cfg.lidar
    clock = VirtualClock()
    lidar = Lidar(twin.physics, clock, Bus(clock), cfg, autostart=False)
    lidar.start_motor(grid_us=twin.grid_us, samplers=[])
    grid_us, t_us = twin.grid_us, 0
    block = 10 * lidar.scan_us // grid_us  # grid instants of about 10 rotations
    now = timer
    best_rotation = best_one = float("inf")
    for _ in range(SCAN_REPEATS // 10):
        seq0, t0 = lidar.seq, now()
        for _k in range(block):
            lidar.on_sample(t_us)
            t_us += grid_us
        best_rotation = min(best_rotation, (now() - t0) / (lidar.seq - seq0))
    for _ in range(SCAN_REPEATS):
        t0 = now()
        lidar.scan_now()
        best_one = min(best_one, now() - t0)
    return best_rotation * 1e6, best_one * 1e6


def sensor_figures(cfg: TwinConfig, sim_s: float) -> dict:
    """Sensor cost figures.

    Parameters
    ----------
    cfg : TwinConfig
        Parameters (``imu:`` and ``lidar:`` sections included).
    sim_s : float
        Simulated duration of each timed run, s. Each repeat times the twin with
        sensors, bare ``mj_step`` from the state it reached, and the twin without
        sensors, interleaved (the machine is noisy: figures measured minutes apart
        are not comparable); each ratio is the median of the repeats' ratios.

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
    with_t, without_t, bare_t = [], [], []
    twin = None
    for _ in range(REPEATS):  # interleaved so that a disturbance hits all three
        cpu_s, twin = twin_run_s(cfg, sim_s, sensors=True)
        with_t.append(cpu_s)
        bare_t.append(bare_steps_s(twin.physics, sim_s))
        without_t.append(twin_run_s(cfg, sim_s, sensors=False)[0])
    twin.physics.forward()
    scan_groups_us, scan_one_us = lidar_scan_cost_us(twin)
    return {
        "sensors_s_per_sim_s": round(statistics.median(with_t) / sim_s, 5),
        **paired_ratio("sensors_ratio", with_t, bare_t),
        **paired_ratio("twin_no_sensors_ratio", without_t, bare_t),
        "lidar_scan_us": round(scan_groups_us, 1),
        "lidar_scan_one_call_us": round(scan_one_us, 1),
        "lidar_beams_per_scan": twin.lidar.n_beams,
    }
