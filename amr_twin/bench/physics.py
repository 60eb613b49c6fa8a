"""The floor of ``amr-twin bench``: bare MuJoCo physics along the loop's own path; the figures'
spread.

Every figure of the bench is a ratio against one floor: ``mj_step`` alone on the loop
scenario's model (the twin's own: world, robot, contact model, timestep), stepped over the
path the twin drove. A timed twin run advances in :data:`PIECES` pieces; at each piece's
start (untimed) its physics is cloned, and the floor steps a fresh clone of each for as many
steps as the twin stepped in that piece, with the actuation held as it was there. Times are
the process' CPU time (:data:`timer`).
"""

from __future__ import annotations

import statistics
import time
from dataclasses import dataclass

from amr_twin.sim.physics import Physics

REPEATS = 5
"""Rounds of every figure (each round runs every figure once, each between two floors)."""
PIECES = 8
"""Pieces of a timed run: the floor's snapshots are taken between them."""
timer = time.process_time
"""Clock of every benchmark figure, s (CPU time of this process)."""


@dataclass(frozen=True)
class Spread:
    """Median, extremes and quartiles of a figure's repeats (``values``, in the order measured)."""

    median: float
    low: float
    high: float
    q1: float
    q3: float
    values: tuple[float, ...]


def spread(values: list[float]) -> Spread:
    """The :class:`Spread` of ``values`` (at least one); quartiles by ``statistics.quantiles``
    (inclusive)."""
    vals = [float(v) for v in values]
    if not vals:
        raise ValueError("spread: no values")
    q1, _q2, q3 = (
        statistics.quantiles(vals, n=4, method="inclusive") if len(vals) > 1 else (vals[0],) * 3
    )
    return Spread(statistics.median(vals), min(vals), max(vals), q1, q3, tuple(vals))


@dataclass
class FloorPath:
    """Snapshots of a twin's physics along a timed run: ``(clone, steps the twin then took)``
    each."""

    pieces: list[tuple[Physics, int]]

    @property
    def steps(self) -> int:
        """Physics steps of the whole path."""
        return sum(n for _p, n in self.pieces)


def timed_advance(twin, sim_s: float, snapshot: bool = False) -> tuple[float, FloorPath | None]:
    """Advance ``twin`` by ``sim_s`` in :data:`PIECES` pieces: its CPU s, and with ``snapshot``
    the :class:`FloorPath` it stepped (the clones are taken outside the timing)."""
    ends_us = [twin.clock.now_us + round(sim_s * 1e6 * (i + 1) / PIECES) for i in range(PIECES)]
    shots, cpu = [], 0.0
    for end_us in ends_us:
        if snapshot:
            shots.append((twin.physics.clone(), twin.t_phys_us))
        t0 = timer()
        twin.advance_to_us(end_us)
        cpu += timer() - t0
    if not snapshot:
        return cpu, None
    marks = [t for _p, t in shots] + [twin.t_phys_us]
    return cpu, FloorPath([(p, (b - a) // twin.dt_us) for (p, a), b in zip(shots, marks[1:])])


def floor_s(path: FloorPath) -> float:
    """CPU s of bare ``mj_step`` over ``path``: a fresh clone of each snapshot (untimed) stepped
    as many steps as the twin took from it, in one C call each."""
    cpu = 0.0
    for physics, nstep in path.pieces:
        if nstep <= 0:
            continue
        clone = physics.clone()
        t0 = timer()
        clone.step(nstep)
        cpu += timer() - t0
    return cpu


def bare_steps_s(physics: Physics, sim_s: float) -> float:
    """CPU seconds of ``sim_s`` of mj_step alone on ``physics``' model and data as they are now."""
    nstep = int(round(sim_s / physics.timestep_s))
    t0 = timer()
    physics.step(nstep)  # one mj_step call of nstep steps in C
    return timer() - t0


TYRES_START = (-8.0, 0.0, 0.0)
"""Start of the tyre comparison: the west end of the warehouse's central aisle, heading along it."""


def _driving(cfg) -> Physics:
    """The robot settled at :data:`TYRES_START` in the warehouse, then driven 1 s straight at a
    constant duty (about 0.5 m/s: 16 s stay in the aisle)."""
    from amr_twin.model.build import build
    from amr_twin.base.pins import DriverPins
    from amr_twin.sim.plant import Plant

    physics = Physics(build(cfg, world="warehouse", start_xy_yaw=TYRES_START).model)
    physics.settle(0.5)
    Plant(
        physics,
        cfg.driver,
        (cfg.driver_left, cfg.driver_right),
        (cfg.motor_left, cfg.motor_right),
        cfg.battery,
    ).apply((DriverPins(8, 1, 0, 1), DriverPins(8, 1, 0, 1)))
    physics.step(1000)
    return physics


def tyre_ratios(cfg, sim_s: float, repeats: int = REPEATS) -> list[float]:
    """Bare physics with the brush tyres (:mod:`amr_twin.sim.tyres`) over the rigid contact of the
    model before them (``wheel.tyre_slip`` off): each repeat steps a copy of each settled, driving
    robot, interleaved; the repeats' ratios (a comparison of two bare physics, not against the
    floor)."""
    from amr_twin.model.config import with_values

    brush = _driving(with_values(cfg, {"wheel.tyre_slip": True}))
    rigid = _driving(with_values(cfg, {"wheel.tyre_slip": False}))
    return [
        bare_steps_s(brush.clone(), sim_s) / bare_steps_s(rigid.clone(), sim_s)
        for _ in range(repeats)
    ]
