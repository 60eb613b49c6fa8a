"""The whole twin against bare physics, on the same scenario in the same run.

Scenario: chapter 5 run 3 (linear 0.7 m/s, 16 s, faithful firmware) in the
warehouse's central aisle, from :data:`BENCH_START`: the faithful firmware veers
right (as the thesis robot does), and this start heading keeps its 11 m path in the
aisle, touching nothing but the floor. The twin figure is the CPU time of
:meth:`Twin.advance` (physics, plant, hall edges, firmware, rosserial, PC nodes,
recorder). The bare figure steps the same model from the state the twin reached,
for as many steps, with the actuation held, in one ``mj_step(m, d, n)`` call: the
cost of the physics alone. (From the old start, (0, 0, 0), the robot struck a rack
after 7.3 s and pushed against it: the bare figure, stepped from that contact, cost
more per step than the twin's run on average, and the ratios came out low and
noisy, 0.98 to 1.23 for the same code.)
"""

from __future__ import annotations

import statistics

from amr_twin.bench.physics import REPEATS, bare_steps_s, paired_ratio, timer
from amr_twin.model.config import TwinConfig
from amr_twin.sim.loop import Twin, TwinOptions


BENCH_START = (-8.0, 0.5, 0.5)
"""Start pose of the scenario, ``(x_m, y_m, yaw_rad)``: the west end of the central aisle, heading
0.5 rad left of it (the veer turns the path back along the aisle; tests/bench check it stays clear)."""


def twin_run_s(cfg: TwinConfig, sim_s: float, firmware: str = "faithful",
               sensors: bool = False) -> tuple[float, Twin]:
    """CPU time (:data:`~amr_twin.bench.physics.timer`) of ``sim_s`` of the scenario (linear 0.7 m/s), and the twin."""
    twin = Twin(cfg, TwinOptions(firmware=firmware, sensors=("imu", "lidar") if sensors else (),
                                 start_xy_yaw=BENCH_START))
    twin.client.linear(0.7)
    t0 = timer()
    twin.advance(sim_s)
    return timer() - t0, twin


def twin_figures(cfg: TwinConfig, sim_s: float, firmware: str = "faithful") -> dict:
    """``twin_s_per_sim_s``, ``bare_physics_s_per_sim_s`` (same scenario) and their ``ratio``.

    Repeats are interleaved (twin, bare, twin, bare, ...) so that a disturbance of
    the machine hits both; each figure is the median of its repeats, the ratio the
    median of the repeats' paired ratios, with each of them and the ratio of the medians
    beside it (:func:`~amr_twin.bench.physics.paired_ratio`).
    """
    twin_t, bare_t = [], []
    for _ in range(REPEATS):
        cpu_s, twin = twin_run_s(cfg, sim_s, firmware)
        twin_t.append(cpu_s)
        bare_t.append(bare_steps_s(twin.physics, sim_s))
    twin_s, bare_s = statistics.median(twin_t), statistics.median(bare_t)
    return {
        "twin_scenario": f"chapter 5 run 3: linear 0.7 m/s, {sim_s:g} s, {firmware}, from {BENCH_START}",
        "twin_collisions": len(twin.collisions.collisions),
        "twin_s_per_sim_s": round(twin_s / sim_s, 5),
        "bare_physics_s_per_sim_s": round(bare_s / sim_s, 5),
        **paired_ratio("ratio", twin_t, bare_t),
        "realtime_factor_twin": round(sim_s / twin_s, 1),
        "repeats": REPEATS,
    }
