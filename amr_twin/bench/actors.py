"""Cost of the actors: the twin with four people and pallet jacks against the same twin without.

Scenario: the twin benchmark's (chapter 5 run 3 from :data:`~amr_twin.bench.twin.BENCH_START`,
linear 0.7 m/s, the central aisle) with :data:`BENCH_ACTORS` walking loops the robot never
reaches (two people and a jack in the side aisles, a person crossing the central aisle beyond
the robot's 11 m): in the LiDAR's view, touching nothing. Each repeat runs, interleaved, the
twin with sensors and actors, bare ``mj_step`` of its model from the state it reached, the twin
with sensors and no actor, and the same two pairs without sensors; each ratio is the median of
the repeats' ratios (the machine is noisy). With actors the LiDAR casts every 20 ms instead of
once a rotation (:class:`~amr_twin.sim.loop.Twin`): ``actors_sensors_over_sensors`` includes that.
"""

from __future__ import annotations

import statistics

from amr_twin.bench.physics import REPEATS, bare_steps_s, paired_ratio, timer
from amr_twin.bench.twin import BENCH_START
from amr_twin.model.actors import Actor
from amr_twin.model.config import TwinConfig
from amr_twin.sim.loop import Twin, TwinOptions

BENCH_ACTORS = (
    Actor("person", ((-7.5, 5.5), (7.5, 5.5)), 1.3, loop=True),            # the north side aisle
    Actor("person", ((7.0, 5.0), (-7.0, 5.0)), 1.0, start_s=0.5, loop=True),
    Actor("pallet_jack", ((-7.0, -5.5), (7.0, -5.5)), 1.0, loop=True),      # the south side aisle
    Actor("person", ((6.0, 2.4), (6.0, -2.4)), 1.2, loop=True),             # across the aisle, beyond the robot
)


def actors_run_s(cfg: TwinConfig, sim_s: float, sensors: bool, actors: tuple = BENCH_ACTORS) -> tuple[float, Twin]:
    """CPU time of ``sim_s`` of the scenario with ``actors`` (and the IMU and LiDAR with ``sensors``), and the twin."""
    twin = Twin(cfg, TwinOptions(sensors=("imu", "lidar") if sensors else (), start_xy_yaw=BENCH_START,
                                 actors=actors))
    twin.client.linear(0.7)
    t0 = timer()
    twin.advance(sim_s)
    return timer() - t0, twin


def actor_figures(cfg: TwinConfig, sim_s: float) -> dict:
    """``actors_ratio`` (twin with sensors and the four actors / bare physics of its model),
    ``actors_sensors_over_sensors`` (/ the twin with sensors and no actor), ``actors_over_twin``
    (without sensors: with the actors / without), ``actors_s_per_sim_s``, ``actors_engine``
    (``"C"`` or ``"Python (<why>)"``) and ``actors_collisions`` (0: nothing touched)."""
    with_s, without_s, bare, with_t, without_t = [], [], [], [], []
    twin = None
    for _ in range(REPEATS):
        cpu_s, twin = actors_run_s(cfg, sim_s, sensors=True)
        with_s.append(cpu_s)
        bare.append(bare_steps_s(twin.physics, sim_s))
        without_s.append(actors_run_s(cfg, sim_s, sensors=True, actors=())[0])
        with_t.append(actors_run_s(cfg, sim_s, sensors=False)[0])
        without_t.append(actors_run_s(cfg, sim_s, sensors=False, actors=())[0])
    return {
        "actors_s_per_sim_s": round(statistics.median(with_s) / sim_s, 5),
        **paired_ratio("actors_ratio", with_s, bare),
        **paired_ratio("actors_sensors_over_sensors", with_s, without_s),
        **paired_ratio("actors_over_twin", with_t, without_t),
        "actors_engine": twin.actors.engine,
        "actors_collisions": len(twin.collisions.collisions),
    }
