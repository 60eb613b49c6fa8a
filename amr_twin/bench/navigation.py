"""Navigation figures of ``amr-twin bench``: planning, the controllers' cycles, the twin with navigation.

- ``nav_plan_ms_p50`` / ``_p95``: CPU time of a plan on the aisles world's true map (50 x 20 m, 0.05 m
  cells, planned on 0.1 m): :data:`PLANS` seeded start/goal pairs 10-50 m apart, the planner of the
  navigation stack (room to turn kept, shortening); the first plan pools the whole map, later ones
  only what the costmap changed, as in a run.
- ``nav_<controller>_ms_p50`` / ``_p99``: CPU time of a control cycle at 20 Hz (mppi, rpp), measured
  in the twin runs below (the navigator times each call).
- ``nav_<localisation>_<controller>_realtime_factor``: simulated over CPU seconds of the twin with its
  sensors and the whole navigation stack driving from the aisles world's start towards (10, -4.8), after
  the EKF's rest; ``nav_..._ratio``: the same CPU against bare physics (``mj_step``) of as many steps
  from the state reached, in the same repeat (median of the repeats' ratios).
"""

from __future__ import annotations

import math
import statistics

import numpy as np

from amr_twin.bench.physics import bare_steps_s, timer

PLANS = 30
WORLD = "aisles"
GOAL = (10.0, -4.8, math.pi)
SETUPS = (("truth", "rpp"), ("ekf", "mppi"))
REPEATS = 3


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
    return {"nav_plan_ms_p50": round(float(np.median(times)), 2), "nav_plan_ms_p95": round(float(np.percentile(times, 95)), 2),
            "nav_plans": PLANS}


def twin_navigation_figures(cfg, sim_s: float) -> dict:
    from amr_twin.navigation.stack import REST_S, NavigationOptions, attach, true_map
    from amr_twin.sim.loop import Twin, TwinOptions

    static = true_map(cfg, WORLD)
    out = {}
    for loc, ctl in SETUPS:
        factors, ratios, cycles = [], [], []
        for _ in range(REPEATS):
            twin = Twin(cfg, TwinOptions(firmware="improved", world=WORLD, start_xy_yaw=None, visuals=False,
                                         sensors=True))
            nav = attach(twin, cfg, static, NavigationOptions(goals=(GOAL,), localisation=loc, controller=ctl),
                         publish=False)
            twin.advance(REST_S)
            t0 = timer()
            twin.advance(sim_s)
            cpu = timer() - t0
            factors.append(sim_s / cpu)
            ratios.append(cpu / bare_steps_s(twin.physics, sim_s))
            cycles += nav.controller_cpu_s
        key = f"nav_{loc}_{ctl}"
        out[f"{key}_realtime_factor"] = round(statistics.median(factors), 2)
        out[f"{key}_ratio"] = round(statistics.median(ratios), 2)
        if cycles:
            out[f"nav_{ctl}_ms_p50"] = round(1e3 * float(np.median(cycles)), 3)
            out[f"nav_{ctl}_ms_p99"] = round(1e3 * float(np.percentile(cycles, 99)), 3)
    return out


def navigation_figures(cfg, sim_s: float) -> dict:
    """Every navigation figure (module docstring)."""
    return {**planning_figures(cfg), **twin_navigation_figures(cfg, sim_s)}
