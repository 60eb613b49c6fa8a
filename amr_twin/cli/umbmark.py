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
from amr_twin.cli.common import _config, _guard, fail
from amr_twin.cli.options import ConfigOpt, ParamsOpt, SetOpt

RESERVED = ("wheel.tyre_slip", "sim.floor_friction_field")
"""Settings the command's own options choose (--tyres/--no-tyres, --floor-field/--no-floor-field)."""


def umbmark(
    out: Path = typer.Option(..., "--out", help="Output folder: report.md, metrics.json, borenstein.png, "
                             "emax.png, calibration/seed<N>.yaml."),
    seeds: str = typer.Option("0:9", "--seeds", help="Robots, A:B (both included), a,b,c or one seed: each "
                              "draws its tyre radii, track and hall sensors (as amr-twin experiment fusion)."),
    runs: int = typer.Option(5, "--runs", help="Squares per direction and phase (Borenstein: 5)."),
    tyres: bool = typer.Option(True, "--tyres/--no-tyres", help="Brush tyres (with them the same robots are "
                               "also driven with the rigid contact, for the spread) or the rigid contact only."),
    floor_field: bool = typer.Option(True, "--floor-field/--no-floor-field", help="The floor's friction "
                                     "field, drawn per square (acts through the brush tyres)."),
    jobs: Optional[int] = JobsOpt,
    yes: bool = YesOpt,
    progress: bool = typer.Option(True, "--progress/--no-progress", help="Progress bar on stderr."),
    config: Optional[Path] = ConfigOpt, params: Optional[Path] = ParamsOpt, set_: Optional[list[str]] = SetOpt,
) -> None:
    """UMBmark (4 m squares both ways) per robot, its calibration of the odometry, and the squares again."""
    from amr_twin.experiments.fusion_seeds import parse_seeds
    from amr_twin.experiments.umbmark_seeds import MAX_RUNS, SQUARE_S

    jobs, _ = check_common(jobs, "improved", fail)
    try:
        seed_list = parse_seeds(seeds)
    except ValueError as exc:
        fail(str(exc))
    if not 1 <= runs <= MAX_RUNS:
        fail(f"--runs {runs}: must be in 1..{MAX_RUNS} (squares per direction and phase, ~1 s of CPU each)")
    for item in set_ or []:
        key = item.partition("=")[0].strip()
        if key in RESERVED:
            fail(f"--set {key}: chosen by this command's --tyres/--no-tyres and --floor-field/--no-floor-field")
    if params is not None:  # its value was replaced by the options' without a word
        from amr_twin.model.yaml_file import read_yaml

        tree = read_yaml(params, "--params", lambda text: ValueError(text)) if params.is_file() else None
        for key in RESERVED:
            section, name = key.split(".")
            if isinstance(tree, dict) and isinstance(tree.get(section), dict) and name in tree[section]:
                fail(f"--params {params}: {key} is chosen by this command's --tyres/--no-tyres and "
                     "--floor-field/--no-floor-field")
    check_outputs(fail, folders={"--out": out})
    sets = list(set_ or []) + [f"wheel.tyre_slip={str(tyres).lower()}",
                               f"sim.floor_friction_field={str(floor_field).lower()}"]
    cfg = _config(config, params, sets)
    squares = len(seed_list) * runs * 2 * (3 if tyres else 2)  # before and after; the rigid contact's before
    check_estimate(f"experiment umbmark: {squares} squares", squares * SQUARE_S, "umbmark", jobs, "improved",
                   yes, fail)
    _run(cfg, seed_list, runs, tyres, floor_field, jobs, progress, out, _guard)


def _run(cfg, seeds: list[int], runs: int, tyres: bool, floor_field: bool, jobs: int, progress: bool, out: Path,
         guard) -> None:
    import time

    from amr_twin.experiments import umbmark_report, umbmark_seeds
    from amr_twin.experiments.umbmark_square import Profile
    from amr_twin.model.config import with_values

    profile = Profile()
    main = [umbmark_seeds.SeedJob(cfg, s, runs, profile) for s in seeds]
    rigid = ([umbmark_seeds.SeedJob(with_values(cfg, {"wheel.tyre_slip": False}), s, runs, profile, calibrate=False)
              for s in seeds] if tyres else [])
    meta = {"seeds": seeds, "runs": runs, "tyres": tyres, "floor_field": floor_field, "side_m": profile.side_m,
            "profile": {k: getattr(profile, k) for k in profile.__dataclass_fields__}, "firmware": "improved"}

    def work():
        from amr_twin.base.atomic_file import all_or_nothing

        t0 = time.perf_counter()
        done = umbmark_seeds.run(main + rigid, jobs=jobs, progress=progress)
        with all_or_nothing():
            data = umbmark_report.write(done[:len(main)], done[len(main):] or None, cfg, meta, out)
        return data, time.perf_counter() - t0

    data, wall_s = guard(work)
    s = data["summary"]
    typer.echo(f"{'seed':>4s} {'E_max,syst before mm':>21s} {'after mm':>9s} {'reduction':>9s} {'spread mm':>9s}")
    for d in data["per_seed"]:
        typer.echo(f"{d['seed']:4d} {1e3 * d['before']['node']['e_max_syst_m']:21.1f} "
                   f"{1e3 * d['after']['node']['e_max_syst_m']:9.1f} {d['reduction']:9.1f} "
                   f"{1e3 * d['before']['node']['e_nonsyst_rms_m']:9.2f}")
    rigid_text = (f"; spread with the rigid contact {1e3 * s['rigid_spread_before_m']['mean']:.2f} mm"
                  if "rigid_spread_before_m" in s else "")
    typer.echo(f"reduction: median {s['reduction_median']:.1f}, of the means {s['reduction_of_means']:.1f}; "
               f"spread {1e3 * s['spread_before_m']['mean']:.2f} mm{rigid_text}")
    typer.echo(f"wall time {wall_s:.1f} s (jobs {jobs}); wrote {out}/report.md, metrics.json, borenstein.png, "
               "emax.png, calibration/seed<N>.yaml")
