"""The LiDAR's cost per rotation, us (the ``sensors`` figure itself is the twin's:
:mod:`amr_twin.bench.twin`).

The RPLIDAR A1 at 5.5 Hz: 2000 samples/s, the laser pose sampled every 20 ms on the record
grid, the 364 beams of a rotation cast in one call (sensors/lidar.py). CPU time, best of
:data:`SCAN_REPEATS`.
"""

from __future__ import annotations

from amr_twin.bench.physics import timer
from amr_twin.ros.bus import Bus
from amr_twin.sensors.lidar import Lidar
from amr_twin.base.clock import VirtualClock
from amr_twin.assembly.twin import Twin

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


def lidar_figures(twin: Twin) -> dict:
    """``lidar_scan_us`` (one rotation as the twin casts it: pose samples, casts, noise),
    ``lidar_scan_one_call_us`` (the same beams in one ``mj_multiRay``), ``lidar_beams_per_scan``,
    on ``twin`` (a twin with sensors, after its run)."""
    twin.physics.forward()
    scan_groups_us, scan_one_us = lidar_scan_cost_us(twin)
    return {
        "lidar_scan_us": round(scan_groups_us, 1),
        "lidar_scan_one_call_us": round(scan_one_us, 1),
        "lidar_beams_per_scan": twin.sensors["lidar"].n_beams,
    }
