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
from amr_twin.cli.common import _config, _guard, fail
from amr_twin.cli.options import ConfigOpt, ParamsOpt, SetOpt, checked_seed, firmware_option
from amr_twin.navigation.registries import CONTROLLERS, LOCALISATIONS

MAX_EPISODES = 1000
EPISODE_SIM_S = 70.0
"""Simulated time of a typical episode, s: the median time to the goal of the 50 episodes in
docs/explanation/navigation.md was 56-98 s by scenario (66 s on the true map, 74 s on the SLAM
map)."""


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
    from amr_twin.model.worlds import world_path

    jobs, firmware = check_common(jobs, firmware, fail)
    checked_seed(
        seed, fail
    )  # -1 failed in numpy ("expected non-negative integer"), naming no option
    if not 1 <= episodes <= MAX_EPISODES:
        fail(f"--episodes {episodes}: must be in [1, {MAX_EPISODES}]")
    halls, tuning = _halls(world, generated_seeds, tuning_seeds, door_m)
    maps = maps or ("true" if halls else "true,slam")
    kinds = tuple(k.strip() for k in maps.split(","))
    if not kinds or any(k not in ("true", "slam") for k in kinds) or len(set(kinds)) != len(kinds):
        fail(f"--maps {maps!r}: true, slam or true,slam")
    if people not in ("static", "walking", "crossing", "none"):
        fail(f"--people {people!r}: static, walking, crossing or none")
    if halls and kinds != ("true",):
        fail(
            f"--maps {maps}: a generated hall has no mapping drive to build a SLAM map from: "
            f"give --maps true"
        )
    for registry, name in ((LOCALISATIONS, localisation), (CONTROLLERS, controller)):
        try:
            registry.get(name)
        except ValueError as exc:
            fail(str(exc))
    if not halls and (
        not world_path(world).is_file()
        or world_path(world).suffix.lower() not in (".xml", ".yaml", ".yml")
    ):
        fail(
            f"--world {world}: not a world of models/worlds/, an MJCF .xml file nor a ROS map .yaml"
        )
    if not halls and world_path(world).suffix.lower() != ".xml":
        from amr_twin.model.worlds import MapError, load_map

        try:
            load_map(world_path(world))
        except MapError as exc:
            fail(f"--world {exc}")
        if "slam" in kinds and slam_map is None:
            fail(
                f"--world {world}: a ROS map world has no mapping drive to build a SLAM map from: "
                "give --maps true or --slam-map"
            )
    if slam_map is not None and halls:
        fail("--slam-map: a generated hall runs on its true map only")
    if slam_map is not None:
        from amr_twin.model.worlds import MapError, load_map

        try:
            load_map(slam_map)
        except MapError as exc:
            fail(f"--slam-map {exc}")
    elif "slam" in kinds:
        from amr_twin.experiments.navigation.map import mapping_route

        try:
            mapping_route(world)
        except ValueError as exc:
            fail(str(exc))
    check_executor(executor, scheduler, fail)
    check_outputs(fail, folders={"--out": out})
    runs = episodes * (len(halls) if halls else len(kinds))
    check_estimate(
        f"experiment navigation: {episodes} episode(s) on {len(halls) if halls else len(kinds)} "
        f"{'hall' if halls else 'map'}(s)",
        runs * EPISODE_SIM_S,
        "navigation",
        jobs,
        firmware,
        yes,
        fail,
    )
    cfg = _config(config, params, set_)
    client = dask_client(scheduler, scheduler_timeout_s, fail) if executor == "dask" else None

    def work():
        from amr_twin.experiments.navigation import (
            experiment as navigation,
            report as navigation_report,
        )
        from amr_twin.base.atomic_file import all_or_nothing

        out.mkdir(parents=True, exist_ok=True)
        if halls:
            from amr_twin.experiments.navigation import generated_report as hall_report

            data = navigation.run_halls(
                cfg,
                halls,
                tuning,
                episodes,
                seed=seed,
                localisation=localisation,
                controller=controller,
                firmware=firmware,
                jobs=jobs,
                client=client,
                progress=progress,
                people=people,
            )
            with all_or_nothing():
                hall_report.write_worlds(cfg, data, out)
                data.pop("static_maps")
                hall_report.report(data, out)
            return data
        data = navigation.run(
            cfg,
            world,
            episodes,
            seed=seed,
            maps=kinds,
            slam_yaml=None if slam_map is None else str(slam_map),
            slam_stem=out / "slam_map",
            localisation=localisation,
            controller=controller,
            firmware=firmware,
            jobs=jobs,
            client=client,
            progress=progress,
            people=people,
        )
        static_maps = data.pop("static_maps")
        with all_or_nothing():
            navigation_report.plot(data["rows"], static_maps, out)
            navigation_report.report(data, out)
        return data

    try:
        data = _guard(work)
    finally:
        if client is not None:
            client.close()
    if halls:
        for group, s in data["summary"].items():
            for trips, d in s["doors"].items():
                typer.echo(
                    f"{group:9s} {trips:10s} {d['episodes']:4d} episodes: success "
                    f"{d['success']}, collisions "
                    f"{d['collisions']}, least jamb clearance {_m(d['door_clearance_min_m'])}"
                )
        typer.echo(
            f"wall time {data['wall_s']:.0f} s, CPU {data['cpu_s']:.0f} s; wrote {out}/report.md, "
            "metrics.json and a folder per hall"
        )
        return
    for key, v in data["summary"].items():
        ratio = v["travelled_over_optimal_median"]
        typer.echo(
            f"{key:22s} {v['episodes']:4d} episodes: success {100 * v['success_rate']:5.1f} %, "
            f"collisions {v['collisions']}, travelled/optimal median "
            f"{'-' if ratio is None else f'{ratio:.3f}'}, BARN {v['barn_score_mean']:.3f}"
        )
    typer.echo(
        f"wall time {data['wall_s']:.0f} s, CPU {data['cpu_s']:.0f} s; wrote {out}/report.md, "
        "metrics.json, trajectories_*.png"
    )


def _halls(world: str, generated_seeds: str | None, tuning_seeds: str, door_m: float | None):
    """The generated halls to run on (None: ``world`` is not one) and the tuning ones among the
    names."""
    from amr_twin.model.generated_world import GeneratedWorldError, is_generated, name, parse
    from amr_twin.model.world_generator import FORCED_DOOR_RANGE_M

    if door_m is not None and generated_seeds is None:
        fail("--door-m: only with --generated-seeds (one hall: --world generated:SEED?door=W)")
    if door_m is not None and not FORCED_DOOR_RANGE_M[0] <= door_m <= FORCED_DOOR_RANGE_M[1]:
        fail(
            f"--door-m {door_m:g}: must be in [{FORCED_DOOR_RANGE_M[0]:g}, "
            f"{FORCED_DOOR_RANGE_M[1]:g}] m"
        )
    if generated_seeds is None and not is_generated(world):
        return None, []
    if generated_seeds is None:
        try:
            door_m = parse(world)[1]
        except GeneratedWorldError as exc:
            fail(str(exc))
        halls = [world]
    else:
        halls = [name(s, door_m) for s in _seeds("--generated-seeds", generated_seeds)]
    return halls, [name(s, door_m) for s in _seeds("--tuning-seeds", tuning_seeds)]


def _m(value) -> str:
    return "-" if value is None else f"{value:.3f} m"


MAX_HALLS = 1000


def _seeds(option: str, text: str) -> list[int]:
    """``A-B`` or ``A,B,C`` (or ``none``) as a list of seeds; a one-line error otherwise."""
    from amr_twin.model.generated_world import MAX_SEED

    usage = (
        f"{option} {text}: expected A-B, A,B,C or none (integers in [0, {MAX_SEED}], at most "
        f"{MAX_HALLS})"
    )
    if text.strip() == "none":
        return []
    try:
        if "-" in text:
            a, b = (int(v) for v in text.split("-"))
            seeds = list(range(a, b + 1)) if 0 <= a <= b and b - a < MAX_HALLS else []
        else:
            seeds = [int(v) for v in text.split(",")]
    except ValueError:
        seeds = []
    if (
        not seeds
        or len(seeds) > MAX_HALLS
        or len(set(seeds)) != len(seeds)
        or not all(0 <= v <= MAX_SEED for v in seeds)
    ):
        fail(usage)
    return seeds
