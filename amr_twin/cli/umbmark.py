"""``amr-twin experiment umbmark``: Borenstein and Feng's UMBmark on the twin's robots.

Per seed (the robot the fusion experiment draws) ``--runs`` squares each way, UMBmark, the
odometry node's calibration written and the squares driven again with it; with the brush tyres
(the default) the same robots are also driven with the rigid contact, so that the report shows the
non-systematic spread with and without them. Every option is checked before the first square.
"""

from __future__ import annotations

from pathlib import Path
from typing import Optional

import typer

from amr_twin.cli.checks import JobsOpt, YesOpt, check_common, check_estimate, check_outputs
from amr_twin.cli.common import _config, _guard, checked, fail
from amr_twin.cli.options import ConfigOpt, ParamsOpt, SetOpt


def umbmark(
    out: Path = typer.Option(
        ...,
        "--out",
        help="Output folder: report.md, metrics.json, borenstein.png, "
        "emax.png, calibration/seed<N>.yaml.",
    ),
    seeds: str = typer.Option(
        "0:9",
        "--seeds",
        help="Robots, A:B (both included), a,b,c or one seed: each "
        "draws its tyre radii, track and hall sensors (as amr-twin experiment fusion).",
    ),
    runs: int = typer.Option(5, "--runs", help="Squares per direction and phase (Borenstein: 5)."),
    tyres: bool = typer.Option(
        True,
        "--tyres/--no-tyres",
        help="Brush tyres (with them the same robots are "
        "also driven with the rigid contact, for the spread) or the rigid contact only.",
    ),
    floor_field: bool = typer.Option(
        True,
        "--floor-field/--no-floor-field",
        help="The floor's friction field, drawn per square (acts through the brush tyres).",
    ),
    jobs: Optional[int] = JobsOpt,
    yes: bool = YesOpt,
    progress: bool = typer.Option(True, "--progress/--no-progress", help="Progress bar on stderr."),
    config: Optional[Path] = ConfigOpt,
    params: Optional[Path] = ParamsOpt,
    set_: Optional[list[str]] = SetOpt,
) -> None:
    """UMBmark (4 m squares both ways) per robot, its calibration of the odometry, and the squares
    again."""
    from amr_twin.experiments.umbmark.seeds import SQUARE_S
    from amr_twin.experiments.umbmark.spec import UmbmarkSpec

    jobs, _ = check_common(jobs, "improved", fail)
    spec = UmbmarkSpec(seeds, runs, tyres, floor_field)
    seed_list = checked(spec.validate, set_ or [], params)
    check_outputs(fail, folders={"--out": out})
    sets = list(set_ or []) + [
        f"{key}={str(value).lower()}" for key, value in spec.values().items()
    ]
    cfg = _config(config, params, sets)
    squares = spec.squares(len(seed_list))
    check_estimate(
        f"experiment umbmark: {squares} squares",
        squares * SQUARE_S,
        "umbmark",
        jobs,
        "improved",
        yes,
        fail,
    )
    _run(spec, cfg, jobs, progress, out, _guard)


def _run(spec, cfg, jobs: int, progress: bool, out: Path, guard) -> None:
    import time

    from amr_twin.experiments.umbmark.spec import run

    def work():
        t0 = time.perf_counter()
        return run(spec, cfg, out, jobs=jobs, progress=progress), time.perf_counter() - t0

    data, wall_s = guard(work)
    s = data["summary"]
    typer.echo(
        f"{'seed':>4s} {'E_max,syst before mm':>21s} {'after mm':>9s} {'reduction':>9s} "
        f"{'spread mm':>9s}"
    )
    for d in data["per_seed"]:
        typer.echo(
            f"{d['seed']:4d} {1e3 * d['before']['node']['e_max_syst_m']:21.1f} "
            f"{1e3 * d['after']['node']['e_max_syst_m']:9.1f} {d['reduction']:9.1f} "
            f"{1e3 * d['before']['node']['e_nonsyst_rms_m']:9.2f}"
        )
    rigid_text = (
        f"; spread with the rigid contact {1e3 * s['rigid_spread_before_m']['mean']:.2f} mm"
        if "rigid_spread_before_m" in s
        else ""
    )
    typer.echo(
        f"reduction: median {s['reduction_median']:.1f}, of the means "
        f"{s['reduction_of_means']:.1f}; "
        f"spread {1e3 * s['spread_before_m']['mean']:.2f} mm{rigid_text}"
    )
    typer.echo(
        f"wall time {wall_s:.1f} s (jobs {jobs}); wrote {out}/report.md, metrics.json, "
        f"borenstein.png, "
        "emax.png, calibration/seed<N>.yaml"
    )
