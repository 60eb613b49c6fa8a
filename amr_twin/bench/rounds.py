"""The bench's rounds: every figure run once a round, each followed by the floor (A F B F C F ...).

A round starts with the loop (:func:`~amr_twin.bench.twin.loop_run`), whose path the floor steps
(:mod:`amr_twin.bench.physics`); then each other figure's run, the floor again right after each.
Every figure runs once untimed before the first round (:data:`WARM_UP_S`).
A figure's ratio in a round is its CPU s per simulated s over that of the floor measured right
after it (a drift of the machine hits both sides alike); :func:`summary` gives each figure's
median and spread over the rounds, and the floor's over all its measurements.
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
    """Per figure (by name, the loop first): its runs' CPU s per simulated s and the floor's right
    after each, and the :class:`Timed` runs; ``floor_steps``: steps of a floor measurement."""

    cpu: dict[str, list[float]] = field(default_factory=dict)
    floor: dict[str, list[float]] = field(default_factory=dict)
    runs: dict[str, list[Timed]] = field(default_factory=dict)

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
    """``repeats`` rounds of the loop and ``figures``, each run followed by the floor (module
    notes)."""
    rounds = Rounds()
    for fig in (
        Figure("loop", "", loop_run),
        *figures,
    ):  # warm-up, untimed: imports and first-use builds
        fig.run(cfg, min(sim_s, WARM_UP_S))
    for r in range(repeats):
        say(f"round {r + 1} of {repeats}")
        loop = loop_run(cfg, sim_s)
        path, dt_s = loop.path, loop.twin.physics.timestep_s

        def floor() -> float:
            return floor_s(path) / (path.steps * dt_s)

        rounds.add("loop", loop, floor())
        for fig in figures:
            run = fig.run(cfg, sim_s)
            rounds.add(fig.name, run, floor())
        loop.path = None  # the snapshots go with the round
    return rounds


def ratio_spread(cpu: list[float], floor: list[float]) -> Spread:
    """The :class:`Spread` of the paired ratios ``cpu[i] / floor[i]`` (both per simulated s)."""
    if len(cpu) != len(floor):
        raise ValueError(f"ratio_spread: {len(cpu)} runs against {len(floor)} floors")
    return spread([a / b for a, b in zip(cpu, floor)])


def summary(rounds: Rounds, dt_s: float) -> dict:
    """``floor`` (its CPU s per simulated s over every measurement, and us a step) and per figure
    ``ratio`` (paired, against the floor) and ``s_per_sim_s``, each a :class:`Spread` as a dict."""
    floors = [f for name in rounds.floor for f in rounds.floor[name]]
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
