"""Chapter 5's specs: which runs, how long, which firmware; the attainable study's draws.

:meth:`Chapter5Spec.validate` and :meth:`AttainableSpec.validate` refuse bad input with a ValueError
of one line naming the field (the CLI's option), from Python as from ``amr-twin experiment
chapter5`` and ``chapter5-attainable``; :func:`run` and :func:`run_attainable` do the work.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from amr_twin.experiments.chapter5 import attainable, experiment as chapter5, spread
from amr_twin.experiments.chapter5.runs import RUNS
from amr_twin.experiments.chapter5.metrics import Chapter5Metrics
from amr_twin.experiments.registry import EXPERIMENTS, Experiment
from amr_twin.model.config import TwinConfig
from amr_twin.base.atomic_file import all_or_nothing
from amr_twin.sim.bounds import duration_problem


@dataclass(frozen=True)
class Chapter5Spec:
    """The eight step experiments of thesis chapter 5.

    Args:
        runs: run numbers to do, ``"1,3"`` (None: all eight).
        duration_s: every run's duration, s (None: each run's own).
        firmware: ``faithful``, ``improved`` or ``avr...`` (avr: also run with faithful, compared).
    """

    runs: str | None = None
    duration_s: float | None = None
    firmware: str = "faithful"

    def numbers(self) -> list[int] | None:
        """The run numbers (None: all), ValueError naming ``--runs``."""
        if self.runs is None:
            return None
        try:
            numbers = [int(v) for v in self.runs.split(",")]
        except ValueError:
            raise ValueError(
                f"--runs {self.runs!r}: expected run numbers 1..8 separated by commas"
            ) from None
        if not all(1 <= n <= len(RUNS) for n in numbers):
            raise ValueError(f"--runs {self.runs!r}: run numbers must lie in 1..{len(RUNS)}")
        if len(set(numbers)) != len(numbers):  # run once, silently
            raise ValueError(f"--runs {self.runs!r}: a run is named twice")
        return numbers

    def check_duration(self) -> None:
        """ValueError unless ``duration_s`` is None or a run's length (``sim.bounds``)."""
        problem = None if self.duration_s is None else duration_problem(self.duration_s)
        if problem:
            raise ValueError(f"--duration-s {self.duration_s:g}: {problem}")

    def validate(self) -> list[int] | None:
        """Every check (ValueError, one line naming the field); the run numbers (None: all)."""
        self.check_duration()
        return self.numbers()

    def longest_run_s(self) -> float:
        """The longest run's simulated seconds (each run is one process' memory)."""
        return self.duration_s or max(r.duration_s for r in RUNS)

    def pass_s(self) -> float:
        """Simulated seconds of one pass over the runs."""
        numbers = self.numbers()
        return sum(
            self.duration_s or r.duration_s for r in RUNS if numbers is None or r.number in numbers
        )

    def passes(self, samples: int = 0) -> int:
        """Passes over the runs: the runs, ``samples`` parameter draws, the reference firmware's
        two with avr, and the rolling-resistance study with every run at its own length (at most a
        pass)."""
        return (
            1
            + samples
            + (2 if self.firmware.startswith("avr") else 0)
            + (1 if self.runs is None and self.duration_s is None else 0)
        )


def run(
    spec: Chapter5Spec,
    cfg: TwinConfig,
    out_dir: Path,
    *,
    jobs: int = 1,
    progress: bool = False,
    record_dir: Path | None = None,
    mcap_dir: Path | None = None,
    draws=None,
) -> Chapter5Metrics:
    """Validate ``spec``, simulate its runs (``jobs`` processes; with ``draws``, an
    :class:`amr_twin.calibration.draws.Draws`, once more per draw), judge them and write
    ``out_dir``'s report with the recordings, all or nothing; the metrics."""
    numbers = spec.validate()
    reference = "faithful" if spec.firmware.startswith("avr") else None
    with all_or_nothing():
        results = chapter5.run(
            cfg,
            jobs=jobs,
            firmware=spec.firmware,
            runs=numbers,
            duration_s=spec.duration_s,
            progress=progress,
            record_dir=record_dir,
            mcap_dir=mcap_dir,
            reference_firmware=reference,
        )
        if numbers is None and spec.duration_s is None and spec.firmware == "faithful":
            results["attainable"] = attainable.committed(cfg)  # the runs the study judged
        if draws is not None:
            results["spread"] = spread.run(
                cfg,
                draws,
                jobs=jobs,
                firmware=spec.firmware,
                runs=numbers,
                duration_s=spec.duration_s,
                progress=progress,
            )
            results["spread_summary"] = spread.summarise(results, results["spread"])
        chapter5.plot(results, out_dir)
        return chapter5.report(results, out_dir)


@dataclass(frozen=True)
class AttainableSpec:
    """Which chapter 5 findings a plant inside the sourced ranges meets.

    Args:
        samples: plants drawn inside the ranges, 1 to ``MAX_SAMPLES`` (each runs the eight runs).
        seed: seed of the draws, >= 0 (same seed, same plants and results).
    """

    samples: int = 64
    seed: int = 0

    def validate(self) -> None:
        """Every check (ValueError, one line naming the field)."""
        if not 1 <= self.samples <= attainable.MAX_SAMPLES:
            raise ValueError(f"--samples {self.samples}: must be in 1..{attainable.MAX_SAMPLES}")
        if self.seed < 0:
            raise ValueError(f"--seed {self.seed}: must be >= 0")


def run_attainable(spec: AttainableSpec, cfg: TwinConfig, *, jobs: int = 1, progress=None) -> dict:
    """Validate ``spec``, draw its plants and run the study (``progress(i, n)`` after each
    draw); the summary of :func:`amr_twin.experiments.chapter5.attainable.summary`."""
    spec.validate()
    draws = attainable.study(cfg, spec.samples, spec.seed, jobs=jobs, progress=progress)
    return attainable.summary(draws)


EXPERIMENTS.register(
    "chapter5",
    Experiment(
        "chapter5",
        Chapter5Spec,
        run,
        Chapter5Metrics,
        "thesis chapter 5's step experiments judged against its bands",
    ),
)
EXPERIMENTS.register(
    "chapter5-attainable",
    Experiment(
        "chapter5-attainable",
        AttainableSpec,
        run_attainable,
        dict,
        "which chapter 5 findings a plant inside the sourced ranges meets",
    ),
)
