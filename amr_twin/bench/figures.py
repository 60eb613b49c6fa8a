"""Every figure printed by ``amr-twin bench``, each a ratio against one floor measured in the same
rounds.

:func:`run_benchmarks` runs the rounds (:mod:`amr_twin.bench.rounds`: the loop, its sensors, the
actors, a recording, ``--firmware avr``, the navigation stack, each between two floors of
:mod:`amr_twin.bench.physics`), then the figures that are not per simulated second (the LiDAR's
scan, planning, the controllers' cycles, the tyres' bare physics against the rigid contact's);
:func:`report_lines` is the command's text.
"""

from __future__ import annotations

import os

from amr_twin.bench.physics import REPEATS, spread, tyre_ratios
from amr_twin.bench.rounds import Figure, ratio_of, run_rounds, spread_dict, summary
from amr_twin.bench.twin import SCENARIO
from amr_twin.model.config import TwinConfig

FLOOR = (
    "bare mj_step of the loop's model along the loop's own path "
    "(same world, contact model, timestep)"
)
LOOP = (
    "the twin without sensors: physics, plant, hall edges, firmware, rosserial, PC nodes, recorder"
)


def bench_figures(cfg: TwinConfig) -> tuple[Figure, ...]:
    """The figures timed in the rounds besides the loop, in their order (``avr`` only with its
    tools)."""
    from amr_twin.bench.actors import actors_no_sensors_run, actors_run
    from amr_twin.bench.navigation import SETUPS, nav_run
    from amr_twin.bench.recording import recording_run
    from amr_twin.bench.twin import avr_run, sensors_run
    from amr_twin.controllers.avr_build import missing_tools

    figs = [
        Figure("sensors", "the loop with the IMU at 100 Hz and the LiDAR at 5.5 Hz", sensors_run),
        Figure(
            "actors",
            "sensors, and four people and pallet jacks walking in the LiDAR's view",
            actors_run,
        ),
        Figure(
            "actors_no_sensors", "the loop and the four actors, no sensors", actors_no_sensors_run
        ),
        Figure(
            "recording", "the loop with the capture attached and its .rrd written", recording_run
        ),
    ]
    if not missing_tools():
        figs.append(
            Figure("avr", "the loop with --firmware avr (the emulated ATmega2560)", avr_run)
        )
    for loc, ctl in SETUPS:
        figs.append(
            Figure(
                f"nav_{loc}_{ctl}",
                f"sensors and the navigation stack ({loc}, {ctl}) in the aisles "
                "world, improved firmware",
                lambda cfg, sim_s, loc=loc, ctl=ctl: nav_run(cfg, sim_s, loc, ctl),
            )
        )
    return tuple(figs)


def run_benchmarks(
    cfg: TwinConfig, sim_s: float = 16.0, repeats: int = REPEATS, say=lambda text: None
) -> dict:
    """All figures of the bench in one run (module notes): the JSON ``amr-twin bench --json``
    prints."""
    from amr_twin.bench.navigation import SETUPS, cycle_figures, planning_figures
    from amr_twin.bench.sensors import lidar_figures
    from amr_twin.controllers.avr_build import missing_tools
    from amr_twin.sim import tyres

    load_before = os.getloadavg()
    figs = bench_figures(cfg)
    rounds = run_rounds(cfg, sim_s, figs, repeats, say)
    loop = rounds.runs["loop"][-1].twin
    out = {
        "timer": "process_time",
        "repeats": repeats,
        "sim_s": sim_s,
        "scenario": SCENARIO,
        "cores": os.cpu_count(),
        **summary(rounds, loop.physics.timestep_s),
    }
    out["floor"]["what"] = f"{FLOOR}; dt {loop.physics.timestep_s:g} s, tyres {tyres.engine()}"
    whats = {"loop": LOOP, **{f.name: f.what for f in figs}}
    for name, fig in out["figures"].items():
        fig["what"] = whats[name]
    say("the figures that are not per simulated second")
    sensors = rounds.runs["sensors"][-1].twin
    details = {
        "actors_over_sensors": ratio_of(rounds, "actors", "sensors"),
        "actors_no_sensors_over_loop": ratio_of(rounds, "actors_no_sensors", "loop"),
        "collisions": max(
            r.info.get("collisions", 0) for runs in rounds.runs.values() for r in runs
        ),
        "actors_engine": rounds.runs["actors"][-1].info["engine"],
        "rrd_bytes": rounds.runs["recording"][-1].info["rrd_bytes"],
        **lidar_figures(sensors),
        **planning_figures(cfg),
        "tyres_physics_ratio": spread_dict(spread(tyre_ratios(cfg, sim_s, repeats)), 3),
    }
    for _loc, ctl in SETUPS:
        details.update(cycle_figures(ctl, rounds.runs[f"nav_{_loc}_{ctl}"]))
    problem = missing_tools()
    if problem:
        details["avr_skipped"] = problem
    details["native_engines"] = native_engines()
    out["details"] = details
    out["load_average"] = {
        "before": [round(v, 2) for v in load_before],
        "after": [round(v, 2) for v in os.getloadavg()],
    }
    return out


def native_engines() -> dict[str, str]:
    """``"C"`` or ``"Python (<why>)"`` for every C helper, by name
    (:mod:`amr_twin.base.native_build`)."""
    from amr_twin.estimation import drive_arcs
    from amr_twin.navigation import mppi
    from amr_twin.sensors import hall_edges, imu_errors, lidar_kernels
    from amr_twin.sim import actors, battery, collisions, grid_steps, rolling_resistance, tyres
    from amr_twin.base.native_build import native_status

    helpers = (
        grid_steps,
        rolling_resistance,
        battery,
        collisions,
        actors,
        hall_edges,
        imu_errors,
        lidar_kernels,
        tyres,
        mppi,
        drive_arcs,
    )
    return {module.C_SOURCE.stem: native_status(module.C_SOURCE) for module in helpers}


def _span(d: dict, fmt: str) -> str:
    return f"{d['min']:{fmt}}-{d['max']:{fmt}}"


def report_lines(r: dict) -> list[str]:
    """The text of ``amr-twin bench`` for the result ``r`` of :func:`run_benchmarks` (the floor
    first,
    then each figure as a ratio against it with its spread, then the other figures)."""
    fl, us = r["floor"]["s_per_sim_s"], r["floor"]["us_per_step"]
    la = r["load_average"]
    lines = [
        f"CPU time ({r['timer']}), {r['repeats']} rounds of {r['sim_s']:g} simulated s, "
        "each figure between two floors "
        f"(ratio over their mean); scenario: {r['scenario']}",
        f"load average (1, 5, 15 min) {' '.join(map(str, la['before']))} before, "
        f"{' '.join(map(str, la['after']))} after, on {r['cores']} cores",
        f"floor: {r['floor']['what']}",
        f"  {fl['median']:.5f} s per simulated s ({us['median']:.2f} us a step), "
        f"min-max {_span(fl, '.5f')}, "
        f"{len(fl['repeats'])} measurements",
        f"{'figure':20s} {'ratio':>6s} {'min-max':>12s} {'IQR':>12s} {'s/sim s':>8s}  what",
    ]
    for name, f in r["figures"].items():
        ratio = f["ratio"]
        lines.append(
            f"{name:20s} {ratio['median']:6.3f} {_span(ratio, '.3f'):>12s} "
            f"{ratio['q1']:.3f}-{ratio['q3']:.3f} {f['s_per_sim_s']['median']:8.5f}  {f['what']}"
        )
    for key, value in r["details"].items():
        if isinstance(value, dict) and "median" in value:
            value = f"{value['median']} (min-max {_span(value, '.3f')})"
        lines.append(f"{key:32s} {value}")
    return lines
