"""The benchmark's actors: the twin with four people and pallet jacks walking loops it never
reaches.

Scenario: the twin benchmark's (:mod:`amr_twin.bench.twin`) with :data:`BENCH_ACTORS` (two people
and a jack in the side aisles, a person crossing the central aisle beyond the robot's 11 m): in
the LiDAR's view, touching nothing. With actors the LiDAR casts every 20 ms instead of once a
rotation (:class:`~amr_twin.assembly.twin.Twin`): the ``actors`` figure includes that.
"""

from __future__ import annotations

from amr_twin.bench.twin import Timed, twin_run
from amr_twin.model.actors import Actor
from amr_twin.model.config import TwinConfig

BENCH_ACTORS = (
    Actor("person", ((-7.5, 5.5), (7.5, 5.5)), 1.3, loop=True),  # the north side aisle
    Actor("person", ((7.0, 5.0), (-7.0, 5.0)), 1.0, start_s=0.5, loop=True),
    Actor("pallet_jack", ((-7.0, -5.5), (7.0, -5.5)), 1.0, loop=True),  # the south side aisle
    Actor(
        "person", ((6.0, 2.4), (6.0, -2.4)), 1.2, loop=True
    ),  # across the aisle, beyond the robot
)


def actors_run(
    cfg: TwinConfig, sim_s: float, sensors: bool = True, actors: tuple = BENCH_ACTORS
) -> Timed:
    """``sim_s`` of the scenario with ``actors`` (and the IMU and LiDAR with ``sensors``), timed."""
    timed = twin_run(cfg, sim_s, sensors=sensors, actors=actors)
    timed.info["engine"] = timed.twin.actors.engine
    return timed


def actors_no_sensors_run(cfg: TwinConfig, sim_s: float) -> Timed:
    """The actors without the IMU and LiDAR."""
    return actors_run(cfg, sim_s, sensors=False)
