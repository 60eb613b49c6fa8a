"""Bare MuJoCo physics of the twin's model, the floor every ``amr-twin bench`` figure is quoted against.

Times are the process' CPU time (:data:`timer`, ``time.process_time``), not wall
time: on a shared machine other work delays a run without costing it CPU, which
made wall-clock ratios swing by 2x. Each figure is the median of :data:`REPEATS`
interleaved repeats (twin, bare, twin, bare, ...: a disturbance of the machine
hits both), each ratio the median of the repeats' own ratios; on an idle machine
CPU and wall time agree.
"""

from __future__ import annotations

import statistics
import time

from amr_twin.model.build import build
from amr_twin.model.config import TwinConfig
from amr_twin.sim.physics import Physics
from amr_twin.base.pins import DriverPins
from amr_twin.sim.plant import Plant

REPEATS = 5
timer = time.process_time
"""Clock of every benchmark figure, s (CPU time of this process)."""


RATIOS = ("each *_ratio is the median over the repeats of a paired ratio: the loop's CPU s over bare "
          "physics' CPU s measured right after it in the same repeat (a disturbance of the machine hits both); "
          "*_ratio_repeats lists the paired ratios; *_ratio_of_medians divides the two medians (the *_s_per_sim_s "
          "figures), which pairs numbers from different repeats and differs when the load changes between them")
"""How ``amr-twin bench`` states its ratios (in its JSON as ``ratios``)."""


def paired_ratio(name: str, loop_s: list[float], bare_s: list[float], digits: int = 3) -> dict:
    """``{name: median of the repeats' loop/bare ratios, name_repeats: each, name_of_medians: the
    medians' ratio}`` (see :data:`RATIOS`)."""
    pairs = [a / b for a, b in zip(loop_s, bare_s)]
    return {name: round(statistics.median(pairs), digits), f"{name}_repeats": [round(r, digits) for r in pairs],
            f"{name}_of_medians": round(statistics.median(loop_s) / statistics.median(bare_s), digits)}


def _median_time(func, repeats: int = REPEATS) -> float:
    times = []
    for _ in range(repeats):
        t0 = timer()
        func()
        times.append(timer() - t0)
    return statistics.median(times)


def bare_steps_s(physics: Physics, sim_s: float) -> float:
    """CPU seconds of ``sim_s`` of mj_step alone on ``physics``' model and data as they are now."""
    nstep = int(round(sim_s / physics.timestep_s))
    t0 = timer()
    physics.step(nstep)  # one mj_step call of nstep steps in C
    return timer() - t0


def bare_physics(cfg: TwinConfig, sim_s: float) -> dict:
    """A settled robot driving straight at a constant duty: mj_step only."""
    physics = Physics(build(cfg, world="warehouse").model)
    physics.settle(0.5)
    plant = Plant(cfg, physics)
    pins = (DriverPins(16, 1, 0, 1), DriverPins(16, 1, 0, 1))
    plant.apply(pins)
    physics.step(1000)
    nstep = int(round(sim_s / physics.timestep_s))
    wall = _median_time(lambda: physics.step(nstep))
    physics.check()
    return {
        "physics_us_per_step": round(wall / nstep * 1e6, 2),
        "bare_physics_s_per_sim_s": round(wall / sim_s, 5),
        "realtime_factor_physics": round(sim_s / wall, 1),
        "timestep_s": physics.timestep_s,
    }


TYRES_START = (-8.0, 0.0, 0.0)
"""Start of the tyre comparison: the west end of the warehouse's central aisle, heading along it."""


def _driving(cfg: TwinConfig) -> Physics:
    """The robot settled at :data:`TYRES_START` in the warehouse, then driven 1 s straight at a
    constant duty (about 0.5 m/s: 16 s stay in the aisle)."""
    physics = Physics(build(cfg, world="warehouse", start_xy_yaw=TYRES_START).model)
    physics.settle(0.5)
    Plant(cfg, physics).apply((DriverPins(8, 1, 0, 1), DriverPins(8, 1, 0, 1)))
    physics.step(1000)
    return physics


def tyre_figures(cfg: TwinConfig, sim_s: float) -> dict:
    """Bare physics of the warehouse model with the brush tyres (:mod:`amr_twin.sim.tyres`) against
    the rigid contact of the model before them (``wheel.tyre_slip`` off), in the same run: each
    repeat steps a copy of each settled, driving robot (interleaved), ``tyres_physics_ratio`` the
    median of the repeats' ratios. The target: at most 1.10."""
    from amr_twin.model.config import with_values
    from amr_twin.sim import tyres

    brush = _driving(with_values(cfg, {"wheel.tyre_slip": True}))
    rigid = _driving(with_values(cfg, {"wheel.tyre_slip": False}))
    brush_t, rigid_t = [], []
    for _ in range(REPEATS):
        brush_t.append(bare_steps_s(brush.clone(), sim_s))
        rigid_t.append(bare_steps_s(rigid.clone(), sim_s))
    nstep = int(round(sim_s / brush.timestep_s))
    return {
        "tyres_physics_us_per_step": round(statistics.median(brush_t) / nstep * 1e6, 2),
        "rigid_physics_us_per_step": round(statistics.median(rigid_t) / nstep * 1e6, 2),
        "tyres_physics_ratio": round(statistics.median(b / r for b, r in zip(brush_t, rigid_t)), 3),
        "tyres_engine": tyres.engine(),
    }
