"""Every figure printed by ``amr-twin bench``, each against bare physics in the same run.

:func:`run_benchmarks` puts together bare physics (:mod:`amr_twin.bench.physics`), the whole
twin (:mod:`amr_twin.bench.twin`), its sensors (:mod:`amr_twin.bench.sensors`), four actors
(:mod:`amr_twin.bench.actors`) and the emulated board (:func:`avr_figures`).
"""

from __future__ import annotations

from amr_twin.bench.physics import RATIOS, bare_physics, tyre_figures
from amr_twin.model.config import TwinConfig


def avr_figures(cfg: TwinConfig, sim_s: float) -> dict:
    """The twin with ``--firmware avr`` (the sketch on the emulated ATmega2560), same scenario.

    ``avr_ratio`` against bare physics measured in the same repeats, ``avr_realtime_factor``
    simulated over CPU seconds; ``avr_skipped`` names what is missing when the Debian packages
    are not installed.
    """
    from amr_twin.controllers.avr_build import missing_tools
    from amr_twin.bench.twin import twin_figures

    problem = missing_tools()
    if problem:
        return {"avr_skipped": problem}
    avr = twin_figures(cfg, sim_s, firmware="avr")
    return {"avr_twin_s_per_sim_s": avr["twin_s_per_sim_s"], "avr_ratio": avr["ratio"],
            "avr_ratio_repeats": avr["ratio_repeats"], "avr_ratio_of_medians": avr["ratio_of_medians"],
            "avr_realtime_factor": avr["realtime_factor_twin"]}


def run_benchmarks(cfg: TwinConfig, sim_s: float = 16.0) -> dict:
    """All benchmark figures of the twin, measured in one run.

    ``physics_us_per_step``: settled robot driving at a constant duty in the
    warehouse (``straight_bare_physics_s_per_sim_s``: not the loop scenario's bare figure).
    ``twin_s_per_sim_s`` / ``bare_physics_s_per_sim_s`` / ``ratio``: the whole twin against bare
    physics on one scenario (:mod:`amr_twin.bench.twin`; how the ratios are taken: ``ratios``);
    ``avr_*``: the same with the emulated board (:func:`avr_figures`).
    ``tyres_*`` and ``rigid_physics_us_per_step``: bare physics with the brush tyres against the
    rigid contact (:func:`~amr_twin.bench.physics.tyre_figures`).
    ``rolling_resistance_engine``: ``"C"`` or ``"Python (<why>)"``
    (:mod:`amr_twin.base.native_build`), which the figures were measured with;
    ``native_engines``: the same for every C helper, by name; ``nav_*``: the navigation stack's
    (:mod:`amr_twin.bench.navigation`).
    """
    from amr_twin.bench.twin import twin_figures
    from amr_twin.sensors import hall_edges, imu_errors, lidar_kernels
    from amr_twin.navigation import mppi
    from amr_twin.sim import actors, battery, collisions, grid_steps, rolling_resistance, tyres
    from amr_twin.base.native_build import native_status

    result = bare_physics(cfg, sim_s)
    result["straight_bare_physics_s_per_sim_s"] = result.pop("bare_physics_s_per_sim_s")
    result.update(twin_figures(cfg, sim_s))
    from amr_twin.bench.sensors import sensor_figures  # IMU + LiDAR against the same bare figure
    result.update(sensor_figures(cfg, sim_s))
    from amr_twin.bench.actors import actor_figures  # four people and jacks, with and without sensors
    result.update(actor_figures(cfg, sim_s))
    result.update(avr_figures(cfg, sim_s))
    result.update(tyre_figures(cfg, sim_s))
    from amr_twin.bench.navigation import navigation_figures  # planning, controllers, the twin navigating
    result.update(navigation_figures(cfg, sim_s))
    result["timer"] = "process_time"
    result["ratios"] = RATIOS
    helpers = (grid_steps, rolling_resistance, battery, collisions, actors, hall_edges, imu_errors, lidar_kernels, tyres,
               mppi)
    engines = {module.C_SOURCE.stem: native_status(module.C_SOURCE) for module in helpers}
    result["rolling_resistance_engine"] = engines["rolling_resistance"]
    result["native_engines"] = engines
    return result
