"""``amr-twin experiment navigation``: seeded start/goal episodes on the true and the SLAM map
(docs/explanation/navigation.md).

Every option is checked before the first simulation: the counts, the world, the maps, the SLAM
map file, the localisation and controller, the executor, the output folder.
"""

from __future__ import annotations

from pathlib import Path
from typing import Optional

import typer

from amr_twin.cli.checks import (
    JobsOpt,
    YesOpt,
    check_common,
    check_estimate,
    check_executor,
    check_outputs,
    dask_client,
)
from amr_twin.cli.common import _config, _guard, checked, fail
from amr_twin.cli.options import ConfigOpt, ParamsOpt, SetOpt, firmware_option
from amr_twin.navigation.registries import CONTROLLERS, LOCALISATIONS


def navigation(
    out: Path = typer.Option(
        ...,
        "--out",
        help="Output folder: report.md, metrics.json, trajectories_<map>.png, "
        "the SLAM map (slam_map.yaml/.pgm/.png).",
    ),
    episodes: int = typer.Option(50, "--episodes", help="Start/goal pairs, each run on every map."),
    seed: int = typer.Option(
        0, "--seed", help="Seed of the episodes (episode i: default_rng([seed, i]))."
    ),
    world: str = typer.Option(
        "aisles",
        "--world",
        help="A world of models/worlds/ with a mapping route "
        "(experiments/routes/<world>_mapping.yaml) or give --slam-map; a ROS map .yaml "
        "(walls extruded) with --maps true; or a generated hall generated:SEED[?door=W].",
    ),
    generated_seeds: Optional[str] = typer.Option(
        None,
        "--generated-seeds",
        help="Run on the generated halls "
        "of these seeds (A-B or A,B,C; instead of --world), the true map.",
    ),
    tuning_seeds: str = typer.Option(
        "0-4",
        "--tuning-seeds",
        help="The generated halls tuned on: reported apart "
        "from the held-out ones (A-B, A,B,C or none).",
    ),
    door_m: Optional[float] = typer.Option(
        None,
        "--door-m",
        help="Every doorway of the generated halls this wide, m (else each drawn in 0.85-1.2 m).",
    ),
    maps: Optional[str] = typer.Option(
        None,
        "--maps",
        help="true, slam or true,slam (default: true,slam; true on generated halls).",
    ),
    slam_map: Optional[Path] = typer.Option(
        None, "--slam-map", help="Use this map_server YAML as the SLAM map instead of building one."
    ),
    people: str = typer.Option(
        "walking",
        "--people",
        help="The person scenario: static (standing in an aisle), "
        "walking (an actor crossing the aisle ahead of the robot, amr_twin/model/actors.py), "
        "crossing (the same, not giving way) or none (no person, no pallet jack).",
    ),
    localisation: str = typer.Option("ekf", "--localisation", help=f"{LOCALISATIONS.choices()}."),
    controller: str = typer.Option("mppi", "--controller", help=f"{CONTROLLERS.choices()}."),
    firmware: str = firmware_option("improved"),
    jobs: Optional[int] = JobsOpt,
    executor: str = typer.Option(
        "local", "--executor", help="local (process pool of --jobs) or dask."
    ),
    scheduler: Optional[str] = typer.Option(None, "--scheduler", help="Dask scheduler address."),
    scheduler_timeout_s: float = typer.Option(5.0, "--scheduler-timeout-s"),
    progress: bool = typer.Option(True, "--progress/--no-progress", help="Progress bar on stderr."),
    yes: bool = YesOpt,
    config: Optional[Path] = ConfigOpt,
    params: Optional[Path] = ParamsOpt,
    set_: Optional[list[str]] = SetOpt,
) -> None:
    """Navigate seeded start/goal pairs, some with an unmapped person or pallet jack, on the true
    and SLAM maps."""
    from amr_twin.experiments.navigation.spec import NavigationSpec, drive

    jobs, firmware = check_common(jobs, firmware, fail)
    spec = NavigationSpec(
        episodes,
        seed,
        world,
        generated_seeds,
        tuning_seeds,
        door_m,
        maps,
        slam_map,
        people,
        localisation,
        controller,
        firmware,
    )
    plan = checked(spec.validate)
    check_executor(executor, scheduler, fail)
    check_outputs(fail, folders={"--out": out})
    check_estimate(
        f"experiment navigation: {episodes} episode(s) on {plan.places()} "
        f"{'hall' if plan.halls else 'map'}(s)",
        spec.simulated_s(plan),
        "navigation",
        jobs,
        firmware,
        yes,
        fail,
    )
    cfg = _config(config, params, set_)
    client = dask_client(scheduler, scheduler_timeout_s, fail) if executor == "dask" else None
    try:
        result = _guard(
            lambda: drive(spec, plan, cfg, out, jobs=jobs, client=client, progress=progress)
        )
    finally:
        if client is not None:
            client.close()
    if plan.halls:
        for group, s in result.summary.items():
            for trips, d in s["doors"].items():
                typer.echo(
                    f"{group:9s} {trips:10s} {d['episodes']:4d} episodes: success "
                    f"{d['success']}, collisions "
                    f"{d['collisions']}, least jamb clearance {_m(d['door_clearance_min_m'])}"
                )
        typer.echo(
            f"wall time {result.wall_s:.0f} s, CPU {result.cpu_s:.0f} s; wrote {out}/report.md, "
            "metrics.json and a folder per hall"
        )
        return
    for key, v in result.summary.items():
        ratio = v["travelled_over_optimal_median"]
        typer.echo(
            f"{key:22s} {v['episodes']:4d} episodes: success {100 * v['success_rate']:5.1f} %, "
            f"collisions {v['collisions']}, travelled/optimal median "
            f"{'-' if ratio is None else f'{ratio:.3f}'}, BARN {v['barn_score_mean']:.3f}"
        )
    typer.echo(
        f"wall time {result.wall_s:.0f} s, CPU {result.cpu_s:.0f} s; wrote {out}/report.md, "
        "metrics.json, trajectories_*.png"
    )


def _m(value) -> str:
    return "-" if value is None else f"{value:.3f} m"
