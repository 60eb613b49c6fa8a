"""The payload sweep's spec: its inputs as one typed record, checked before any simulation.

:meth:`PayloadSweepSpec.validate` refuses bad input with a ValueError of one line naming the
field (the CLI's option, ``--masses``), from Python as from ``amr-twin sweep payload``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

from amr_twin.experiments.payload import point
from amr_twin.experiments.payload.result import PointResult
from amr_twin.experiments.registry import EXPERIMENTS, Experiment
from amr_twin.model.config import TwinConfig
from amr_twin.sim.bounds import duration_problem

MAX_SWEEP_POINTS = 10_000
"""Most runs of one sweep: each is a simulation (~0.5 s of CPU for 8 s) and a file in runs/."""


@dataclass(frozen=True)
class SweepGrid:
    """The sweep's values parsed and checked, each kept once (in order), and the repeats dropped."""

    masses: list[float]
    positions: list[str]
    commands: list[str]
    repeated: list

    @property
    def points(self) -> int:
        """Mass x position x command."""
        return len(self.masses) * len(self.positions) * len(self.commands)


@dataclass(frozen=True)
class PayloadSweepSpec:
    """A payload sweep.

    Args:
        masses: ``START:STOP:STEP`` or ``M1,M2,...``, kg.
        positions: named positions (box flush with the deck edges) or ``X:Y`` in m, comma separated.
        commands: ``linear:V``, ``angular:DEG_S:ICC_M``, ``motor:left|right:V``, comma separated.
        duration_s: simulated seconds per point.
        samples: runs per point with drawn parameters (1: the nominal parameters only).
    """

    masses: str = "0:60:5"
    positions: str = "center,front,rear,left,right"
    commands: str = "linear:0.7,angular:60:-1"
    duration_s: float = 8.0
    samples: int = 1

    def check_duration(self) -> None:
        """ValueError unless ``duration_s`` is a run's length (:mod:`amr_twin.sim.bounds`)."""
        if not math.isfinite(self.duration_s):
            raise ValueError(f"--duration-s {self.duration_s}: must be a finite number")
        problem = duration_problem(self.duration_s)
        if problem:
            raise ValueError(f"--duration-s {self.duration_s:g}: {problem}")

    def grid(self, cfg: TwinConfig) -> SweepGrid:
        """The masses, positions and commands parsed and checked against ``cfg``, no repeats."""
        masses = point.parse_masses(self.masses)
        point.check_masses(self.masses, masses)
        positions = [p.strip() for p in self.positions.split(",") if p.strip()]
        for p in positions:
            point.check_on_deck(cfg, p)
        commands = [c.strip() for c in self.commands.split(",") if c.strip()]
        for c in commands:
            point.check_accepted(cfg, c)
        if not positions or not commands:
            raise ValueError("--positions and --commands must name at least one item each")
        masses, dup_m = _unique(masses, float)
        positions, dup_p = _unique(positions, lambda p: point.position_xy_m(cfg, p))
        commands, dup_c = _unique(commands, point.parse_command)
        return SweepGrid(masses, positions, commands, dup_m + dup_p + dup_c)

    def runs(self, grid: SweepGrid) -> int:
        """Simulations of the sweep: each point, and with ``samples`` > 1 once more per draw."""
        return grid.points * (1 + self.samples if self.samples > 1 else 1)

    def check_size(self, grid: SweepGrid) -> None:
        """ValueError when the sweep has more than :data:`MAX_SWEEP_POINTS` runs."""
        runs = self.runs(grid)
        if runs > MAX_SWEEP_POINTS:
            what = (
                f" x (--samples + 1): {runs} runs"
                if self.samples > 1
                else f": {grid.points} points"
            )
            raise ValueError(
                f"--masses x --positions x --commands{what}; at most "
                f"{MAX_SWEEP_POINTS} per sweep (each is a simulation of "
                f"{self.duration_s:g} s and a file in runs/): split the sweep"
            )

    def validate(self, cfg: TwinConfig) -> SweepGrid:
        """Every check against ``cfg`` (ValueError, one line naming the field); the grid."""
        self.check_duration()
        grid = self.grid(cfg)
        self.check_size(grid)
        return grid


def run(spec: PayloadSweepSpec, cfg: TwinConfig, out_dir: Path, **options) -> dict:
    """Validate ``spec`` and run the sweep (:func:`amr_twin.experiments.payload.sweep.run`, whose
    keyword ``options`` pass through: jobs, firmware, client, draws...); its results dict."""
    from amr_twin.experiments.payload import sweep

    grid = spec.validate(cfg)
    return sweep.run(
        cfg,
        out_dir,
        grid.masses,
        grid.positions,
        grid.commands,
        duration_s=spec.duration_s,
        **options,
    )


def _unique(items: list, key) -> tuple[list, list]:
    """``items`` without repeats (by ``key``), in order; and the repeats dropped."""
    seen, kept, dropped = set(), [], []
    for item in items:
        k = key(item)
        (dropped if k in seen else kept).append(item)
        seen.add(k)
    return kept, dropped


EXPERIMENTS.register(
    "payload",
    Experiment(
        "payload",
        PayloadSweepSpec,
        run,
        PointResult,
        "step response, duty, support loads, tilt and slip against payload mass and position",
    ),
)
