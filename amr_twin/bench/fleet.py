"""A world of N robots: CPU time per robot-second of bare physics and of whole robots.

:func:`fleet_floor`, the bench's floor (:mod:`amr_twin.bench.physics`) for a fleet: the warehouse
with N robots in two lanes of its central aisle (:data:`LANES`), built as a fleet is
(:func:`amr_twin.sim.settled_physics.settled_fleet`: visuals on, IMU off, the brush tyres in C),
each robot driving straight ahead at :data:`DRIVE_V`; ``mj_step`` timed in CPU time
(:data:`~amr_twin.bench.physics.timer`), the fleet sizes interleaved round by round.
:func:`fleet_navigation`: the same lanes, every robot whole (firmware, IMU, LiDAR, UWB, odometry)
with its navigation stack driving it :data:`LEG_M` ahead, as ``amr-twin fleet`` runs them.

Figures: docs/explanation/architecture.md#several-robots-in-one-model.
"""

from __future__ import annotations

import statistics
from dataclasses import replace

from amr_twin.bench.physics import timer
from amr_twin.model.config import TwinConfig
from amr_twin.model.robot_starts import fleet_starts
from amr_twin.sim.settled_physics import settled_fleet

LANES = [(x, y, 0.0) for x in (-6.0, -4.5, -3.0, -1.5, 0.0) for y in (-1.0, 1.0)]
"""Start poses (x_m, y_m, yaw_rad) of up to 10 robots, 1.5 m apart along x, 2 m across."""
DRIVE_V = 3.0
"""Phase voltage of every motor, V (about 0.5 m/s)."""
LEG_M = 5.0
"""How far ahead of its start each robot's navigation goal lies, m."""


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
                    physics.motors.set(wheel, "drive", DRIVE_V)
            steps = int(round(sim_s / fleet.world.timestep_s))
            t0 = timer()
            fleet.world.step(steps)
            times[n].append((timer() - t0) / (n * sim_s))
            fleet.world.check()
    return {n: statistics.median(v) for n, v in times.items()}


def fleet_navigation(
    cfg: TwinConfig,
    counts=(1, 8),
    sim_s: float = 5.0,
    rounds: int = 3,
    localisation: str = "ekf",
    controller: str = "mppi",
    shared: bool = True,
) -> dict[int, float]:
    """Median CPU s per robot per simulated s of the whole world's loop for each fleet size in
    ``counts`` (1: the :class:`~amr_twin.assembly.twin.Twin`, visuals on as a fleet's), every
    robot with the IMU and LiDAR (and the EKF's UWB) and the navigation stack of ``localisation``
    and ``controller`` driving to :data:`LEG_M` ahead; ``sim_s`` timed after the stack's rest
    (``REST_S``), ``rounds`` interleaved rounds; ``shared``: the robots share their poses
    (:func:`~amr_twin.navigation.stack.fleet_mates`), else each takes the others for people."""
    times: dict[int, list[float]] = {n: [] for n in counts}
    for _ in range(rounds):
        for n in counts:
            world = _navigating_world(cfg, n, localisation, controller, shared)
            t0 = timer()
            world.advance(sim_s)
            times[n].append((timer() - t0) / (n * sim_s))
    return {n: statistics.median(v) for n, v in times.items()}


def _navigating_world(
    cfg: TwinConfig, n: int, localisation: str, controller: str, shared: bool = True
):
    """The world of ``n`` robots on :data:`LANES`, each navigating :data:`LEG_M` ahead (sharing
    their poses when ``shared`` and ``n`` > 1), run through the stack's rest."""
    from amr_twin.assembly.fleet_world import fleet_world
    from amr_twin.assembly.twin import Twin, TwinOptions
    from amr_twin.navigation.stack import (
        REST_S,
        NavigationOptions,
        attach,
        fleet_mates,
        load_static_map,
    )

    options = TwinOptions(world="warehouse", firmware="improved", sensors=("imu", "lidar"))
    if n == 1:
        world = Twin(cfg, replace(options, start_xy_yaw=LANES[0]))
    else:
        world = fleet_world(cfg, options, LANES[:n])
    static = load_static_map(cfg, "warehouse", None)
    fleet = fleet_mates(cfg) if shared and n > 1 else None
    for i, robot in enumerate(world.robots):
        x, y, yaw = robot.start_xy_yaw
        goal = ((x + LEG_M, y, yaw),)
        nav = NavigationOptions(
            goals=goal, localisation=localisation, controller=controller, seed=i
        )
        attach(robot, cfg, static, nav, publish=False, fleet=fleet)
    world.advance(REST_S + 0.5)
    return world


def fleet_figures(cfg: TwinConfig, counts=(1, 4, 8), rounds: int = 3, sim_s: float = 5.0) -> dict:
    """``amr-twin bench --fleet``: :func:`fleet_navigation` (EKF + MPPI, shared poses) of
    ``counts`` as ``fleet_ms_per_robot_s`` (CPU ms per robot per simulated s by fleet size), each
    size's ratio to the first (``fleet_ratio_to_1``) and its real-time factor in CPU time
    (``fleet_rtf``: simulated s per CPU s of the whole world)."""
    cost = fleet_navigation(cfg, counts, sim_s=sim_s, rounds=rounds)
    return {
        "fleet_ms_per_robot_s": {n: round(c * 1e3, 1) for n, c in cost.items()},
        "fleet_ratio_to_1": {n: round(c / cost[counts[0]], 2) for n, c in cost.items()},
        "fleet_rtf": {n: round(1.0 / (c * n), 2) for n, c in cost.items()},
    }
