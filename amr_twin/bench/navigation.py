"""Navigation figures of ``amr-twin bench``: planning, the controllers' cycles, the twin navigating.

- ``nav_plan_ms_p50`` / ``_p95``: CPU time of a plan on the aisles world's true map (50 x 20 m,
  0.05 m cells, planned on 0.1 m): :data:`PLANS` seeded start/goal pairs 10-50 m apart, the planner
  of the navigation stack (room to turn kept, shortening); the first plan pools the whole map, later
  ones only what the costmap changed, as in a run.
- ``nav_<controller>_ms_p50`` / ``_p99``: CPU time of a control cycle at 20 Hz (mppi, rpp),
  measured in the twin runs of :func:`nav_run` (the navigator times each call).
- the figures ``nav_<localisation>_<controller>``: the twin with its sensors and the whole
  navigation stack in the aisles world (:func:`nav_run`), against the bench's one floor (the loop's
  model in the warehouse: a different world, so the ratio includes the worlds' difference).
"""

from __future__ import annotations

import math

import numpy as np

from amr_twin.bench.physics import timed_advance, timer
from amr_twin.bench.twin import Timed

PLANS = 30
WORLD = "aisles"
GOAL = (10.0, -4.8, math.pi)
SETUPS = (("truth", "rpp"), ("ekf", "mppi"))


def planning_figures(cfg) -> dict:
    from amr_twin.navigation.footprint import robot_footprint
    from amr_twin.navigation.stack import make_costmap, make_planner, true_map

    fp = robot_footprint(cfg)
    costmap = make_costmap(true_map(cfg, WORLD), fp, cfg.navigation)
    planner = make_planner(costmap, fp, cfg.navigation)
    free = costmap.centres_xy_m(*np.nonzero(costmap.static_dist_m >= 0.7))
    rng = np.random.default_rng(0)
    times = []
    while len(times) < PLANS:
        a, b = free[rng.integers(len(free))], free[rng.integers(len(free))]
        if 10.0 <= math.hypot(*(b - a)) <= 50.0:
            t0 = timer()
            planner.plan(a, b)
            times.append(1e3 * (timer() - t0))
    return {
        "nav_plan_ms_p50": round(float(np.median(times)), 2),
        "nav_plan_ms_p95": round(float(np.percentile(times, 95)), 2),
        "nav_plans": PLANS,
    }


def nav_run(cfg, sim_s: float, localisation: str, controller: str) -> Timed:
    """The twin with its sensors and the whole navigation stack (``localisation``, ``controller``)
    driving from the aisles world's start towards :data:`GOAL` after the EKF's rest (untimed),
    ``sim_s`` timed; ``info["cycles"]``: the controller's CPU s a cycle."""
    from amr_twin.navigation.stack import REST_S, NavigationOptions, attach, true_map
    from amr_twin.assembly.twin import Twin, TwinOptions

    twin = Twin(
        cfg,
        TwinOptions(
            firmware="improved",
            world=WORLD,
            start_xy_yaw=None,
            visuals=False,
            sensors=("imu", "lidar"),
        ),
    )
    nav = attach(
        twin,
        cfg,
        true_map(cfg, WORLD),
        NavigationOptions(goals=(GOAL,), localisation=localisation, controller=controller),
        publish=False,
    )
    twin.advance(REST_S)
    cpu, _path = timed_advance(twin, sim_s)
    return Timed(cpu, sim_s, twin, None, {"cycles": list(nav.controller_cpu_s)})


def cycle_figures(controller: str, runs: list[Timed]) -> dict:
    """``nav_<controller>_ms_p50`` and ``_p99`` of the cycles of ``runs`` (none without
    cycles)."""
    cycles = [c for run in runs for c in run.info["cycles"]]
    if not cycles:
        return {}
    return {
        f"nav_{controller}_ms_p50": round(1e3 * float(np.median(cycles)), 3),
        f"nav_{controller}_ms_p99": round(1e3 * float(np.percentile(cycles, 99)), 3),
    }
