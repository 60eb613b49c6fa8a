"""The benchmark's twin runs: the loop, with its sensors, with ``--firmware avr``, each timed by
pieces.

Scenario: chapter 5 run 3 (linear 0.7 m/s, faithful firmware) down the warehouse's central aisle
from :data:`BENCH_START`: the faithful firmware veers right (as the thesis robot does), and this
start heading keeps its 11 m path in the aisle, touching nothing but the floor. The time is the
CPU time of :meth:`Twin.advance` (physics, plant, hall edges, firmware, rosserial, PC nodes,
recorder; the IMU and LiDAR with ``sensors``), in :data:`~amr_twin.bench.physics.PIECES` pieces.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from amr_twin.bench.physics import FloorPath, timed_advance
from amr_twin.model.config import TwinConfig
from amr_twin.assembly.twin import Twin, TwinOptions

BENCH_START = (-8.0, 0.5, 0.5)
"""Start pose of the scenario, ``(x_m, y_m, yaw_rad)``: the west end of the central aisle, heading
0.5 rad left of it (the veer turns the path back along the aisle; tests/bench check it stays
clear)."""
SCENARIO = (
    "chapter 5 run 3: linear 0.7 m/s, faithful firmware, warehouse aisle from (-8, 0.5) heading "
    "0.5 rad"
)


@dataclass
class Timed:
    """One timed run: CPU s of ``sim_s`` simulated s, the twin afterwards, the floor's path (the
    loop's),
    and what the figure adds (``info``)."""

    cpu_s: float
    sim_s: float
    twin: object
    path: FloorPath | None = None
    info: dict = field(default_factory=dict)


def twin_run(
    cfg: TwinConfig,
    sim_s: float,
    firmware: str = "faithful",
    sensors: bool = False,
    actors: tuple = (),
    snapshot: bool = False,
) -> Timed:
    """``sim_s`` of the scenario, timed (and its :class:`FloorPath` with ``snapshot``)."""
    twin = Twin(
        cfg,
        TwinOptions(
            firmware=firmware,
            sensors=("imu", "lidar") if sensors else (),
            start_xy_yaw=BENCH_START,
            actors=actors,
        ),
    )
    twin.client.linear(0.7)
    cpu, path = timed_advance(twin, sim_s, snapshot)
    return Timed(cpu, sim_s, twin, path, {"collisions": len(twin.collisions.collisions)})


def loop_run(cfg: TwinConfig, sim_s: float) -> Timed:
    """The loop without sensors: the floor's path."""
    return twin_run(cfg, sim_s, snapshot=True)


def sensors_run(cfg: TwinConfig, sim_s: float) -> Timed:
    """The loop with the IMU at 100 Hz and the RPLIDAR A1 at 5.5 Hz (their MuJoCo sensors in the
    model)."""
    return twin_run(cfg, sim_s, sensors=True)


def avr_run(cfg: TwinConfig, sim_s: float) -> Timed:
    """The loop with ``--firmware avr`` (the sketch on the emulated ATmega2560)."""
    return twin_run(cfg, sim_s, firmware="avr")
