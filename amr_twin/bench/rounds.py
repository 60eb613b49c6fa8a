"""The bench's rounds: every figure run once a round, each between two floors (F A F B F C F ...).

The floor (:mod:`amr_twin.bench.physics`) steps the path of one untimed run of the loop
(:func:`~amr_twin.bench.twin.loop_run`; every run of the scenario drives the same path to the
bit); every other figure runs once untimed too (:data:`WARM_UP_S`). A round then measures the
floor, the loop, the floor, the next figure, the floor, ... A figure's ratio in a round is its
CPU s per simulated s over the mean of the floors measured just before and just after it (a drift
of the machine hits both sides alike); :func:`summary` gives each figure's median and spread over
the rounds, and the floor's over all its measurements.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable

from amr_twin.bench.physics import REPEATS, Spread, floor_s, spread
from amr_twin.bench.twin import Timed, loop_run
from amr_twin.model.config import TwinConfig

WARM_UP_S = 0.3
"""Simulated s of each figure's untimed run before the rounds (imports, C helpers built, caches
filled)."""


@dataclass(frozen=True)
class Figure:
    """A figure of the bench: its ``name``, one line on ``what`` it runs, ``run(cfg, sim_s)``."""

    name: str
    what: str
    run: Callable[[TwinConfig, float], Timed]


@dataclass
class Rounds:
    """Per figure (by name, the loop first): its runs' CPU s per simulated s, the floor's beside
    each (the mean of the two around it) and the :class:`Timed` runs; ``floors``: every floor
    measurement, CPU s per simulated s, in the order measured."""

    cpu: dict[str, list[float]] = field(default_factory=dict)
    floor: dict[str, list[float]] = field(default_factory=dict)
    runs: dict[str, list[Timed]] = field(default_factory=dict)
    floors: list[float] = field(default_factory=list)

    def add(self, name: str, run: Timed, floor_per_sim_s: float) -> None:
        self.cpu.setdefault(name, []).append(run.cpu_s / run.sim_s)
        self.floor.setdefault(name, []).append(floor_per_sim_s)
        self.runs.setdefault(name, []).append(run)


def run_rounds(
    cfg: TwinConfig,
    sim_s: float,
    figures: tuple[Figure, ...],
    repeats: int = REPEATS,
    say: Callable[[str], None] = lambda text: None,
) -> Rounds:
    """``repeats`` rounds of the loop and ``figures``, each run between two floors (module
    notes)."""
    path_run = loop_run(cfg, sim_s)  # untimed: the floor's path, and the loop's warm-up
    path, dt_s = path_run.path, path_run.twin.physics.timestep_s
    for fig in figures:  # warm-up, untimed: imports and first-use builds
        fig.run(cfg, min(sim_s, WARM_UP_S))
    rounds = Rounds()

    def floor() -> float:
        rounds.floors.append(floor_s(path) / (path.steps * dt_s))
        return rounds.floors[-1]

    for r in range(repeats):
        say(f"round {r + 1} of {repeats}")
        before = floor()
        for fig in (Figure("loop", "", loop_run), *figures):
            run = fig.run(cfg, sim_s)
            run.path = None  # a loop run's snapshots: not needed
            after = floor()
            rounds.add(fig.name, run, 0.5 * (before + after))
            before = after
    return rounds


def ratio_spread(cpu: list[float], floor: list[float]) -> Spread:
    """The :class:`Spread` of the paired ratios ``cpu[i] / floor[i]`` (both per simulated s)."""
    if len(cpu) != len(floor):
        raise ValueError(f"ratio_spread: {len(cpu)} runs against {len(floor)} floors")
    return spread([a / b for a, b in zip(cpu, floor)])


def summary(rounds: Rounds, dt_s: float) -> dict:
    """``floor`` (its CPU s per simulated s over every measurement, and us a step) and per figure
    ``ratio`` (paired, against the floor) and ``s_per_sim_s``, each a :class:`Spread` as a dict."""
    floors = rounds.floors
    out = {
        "floor": {
            "s_per_sim_s": spread_dict(spread(floors), 5),
            "us_per_step": spread_dict(spread([f * dt_s * 1e6 for f in floors]), 2),
        },
        "figures": {},
    }
    for name, cpu in rounds.cpu.items():
        out["figures"][name] = {
            "ratio": spread_dict(ratio_spread(cpu, rounds.floor[name]), 3),
            "s_per_sim_s": spread_dict(spread(cpu), 5),
        }
    return out


def ratio_of(rounds: Rounds, top: str, bottom: str) -> dict:
    """``top``'s CPU over ``bottom``'s paired round by round (e.g. actors over sensors), as a
    :func:`spread_dict`."""
    return spread_dict(ratio_spread(rounds.cpu[top], rounds.cpu[bottom]), 3)


def spread_dict(s: Spread, digits: int) -> dict:
    """``s`` as a JSON object, rounded to ``digits``: median, min, max, q1, q3 and the repeats."""
    return {
        "median": round(s.median, digits),
        "min": round(s.low, digits),
        "max": round(s.high, digits),
        "q1": round(s.q1, digits),
        "q3": round(s.q3, digits),
        "repeats": [round(v, digits) for v in s.values],
    }
