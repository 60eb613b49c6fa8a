"""Bare physics of a world of N robots: CPU time per robot-second of ``mj_step`` alone.

The bench's floor (:mod:`amr_twin.bench.physics`) for a fleet: the warehouse with N robots in
two lanes of its central aisle (:data:`LANES`), built as a fleet is
(:func:`amr_twin.sim.settled_physics.settled_fleet`: visuals on, IMU off, the brush tyres in C),
each robot driving straight ahead at :data:`DRIVE_V`; ``mj_step`` timed in CPU time
(:data:`~amr_twin.bench.physics.timer`), the fleet sizes interleaved round by round.
"""

from __future__ import annotations

import statistics

from amr_twin.bench.physics import timer
from amr_twin.model.config import TwinConfig
from amr_twin.model.robot_starts import fleet_starts
from amr_twin.sim.settled_physics import settled_fleet

LANES = [(x, y, 0.0) for x in (-6.0, -4.5, -3.0, -1.5, 0.0) for y in (-1.0, 1.0)]
"""Start poses (x_m, y_m, yaw_rad) of up to 10 robots, 1.5 m apart along x, 2 m across."""
DRIVE_V = 3.0
"""Phase voltage of every motor, V (about 0.5 m/s)."""


def fleet_floor(
    cfg: TwinConfig, counts=(1, 2, 4, 8), sim_s: float = 2.0, rounds: int = 5
) -> dict[int, float]:
    """Median CPU s per robot per simulated s of ``mj_step`` for each fleet size in ``counts``
    (at most ``len(LANES)``), over ``rounds`` interleaved rounds of ``sim_s`` each."""
    times: dict[int, list[float]] = {n: [] for n in counts}
    for _ in range(rounds):
        for n in counts:
            fleet = settled_fleet(cfg, "warehouse", fleet_starts(LANES[:n]), True, False, 0.3)
            for physics in fleet.robots:
                for wheel in range(2):
                    physics.set_motor(wheel, "drive", DRIVE_V)
            steps = int(round(sim_s / fleet.world.timestep_s))
            t0 = timer()
            fleet.world.step(steps)
            times[n].append((timer() - t0) / (n * sim_s))
            fleet.world.check()
    return {n: statistics.median(v) for n, v in times.items()}
