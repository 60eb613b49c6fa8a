"""``amr-twin experiment chapter5-attainable``: which chapter 5 findings a plant inside its ranges
meets.

The study is :mod:`amr_twin.experiments.chapter5.attainable`; this module checks the options before
the first simulation, shows progress on stderr and writes the JSON summary atomically.
"""

from __future__ import annotations

from pathlib import Path
from typing import Optional

import typer

from amr_twin.cli.checks import JobsOpt, check_common, check_outputs
from amr_twin.cli.common import _config, _guard, checked, fail
from amr_twin.cli.options import ConfigOpt, ParamsOpt, SetOpt


def attainable(
    samples: int = typer.Option(
        64,
        "--samples",
        help="Plants drawn inside the ranges, 1 to 512 (each runs the "
        "eight chapter 5 runs, about 2 s of wall on 2 cores).",
    ),
    seed: int = typer.Option(
        0, "--seed", help="Seed of the draws, >= 0 (same seed, same plants and results)."
    ),
    out: Optional[Path] = typer.Option(
        None, "--out", help="Write the summary and every draw here (JSON)."
    ),
    jobs: Optional[int] = JobsOpt,
    config: Optional[Path] = ConfigOpt,
    params: Optional[Path] = ParamsOpt,
    set_: Optional[list[str]] = SetOpt,
) -> None:
    """Draw plants inside the sourced ranges and count where each thesis finding of §5.1.3-5.1.4
    holds."""
    from amr_twin.experiments.chapter5 import attainable as study
    from amr_twin.experiments.chapter5.spec import AttainableSpec, run_attainable

    spec = AttainableSpec(samples, seed)
    checked(spec.validate)
    jobs, _ = check_common(jobs, "faithful", fail)
    if out is not None:
        check_outputs(fail, files={"--out": out})
    cfg = _config(config, params, set_)

    def work():
        from amr_twin.experiments.runner.executor import write_json

        def progress(i: int, n: int) -> None:
            typer.echo(f"draw {i}/{n}", err=True)

        s = run_attainable(spec, cfg, jobs=jobs, progress=progress)
        if out is not None:
            write_json(out, {"seed": seed, "ranges": study.ranges(cfg), **s})
        return s

    for line in study.lines(_guard(work)):
        typer.echo(line)
