"""``amr-twin experiment navigation``: seeded episodes of start/goal pairs in the warehouse,
measured as nav2 is.

Reasons and measurements: docs/explanation/navigation.md#amr_twinexperimentsnavigationexperiment."""

from __future__ import annotations

import math

import numpy as np

from amr_twin.experiments.navigation.episodes import (
    MAX_APART_M,
    MIN_APART_M,
    SCENARIOS,
    SHARES,
    Episode,
    free_cells,
    place,
)
from amr_twin.experiments.navigation.episode_run import EpisodeRun, timed_episode
from amr_twin.experiments.navigation.result import OPTIMAL, HallsResult, NavigationResult
from amr_twin.model.worlds import Obstacle

MAPS = ("true", "slam")


def episodes(cfg, world: str, n: int, seed: int = 0, people: str = "walking") -> list[Episode]:
    """``n`` episodes, episode ``i`` drawn from ``default_rng([seed, i])`` (module docstring; a
    generated hall's:
    :func:`amr_twin.experiments.navigation.generated.episodes`)."""
    from amr_twin.model.generated_world import is_generated
    from amr_twin.navigation.footprint import robot_footprint
    from amr_twin.navigation.planner import GlobalPlanner
    from amr_twin.navigation.stack import make_costmap, true_map

    if is_generated(world):
        from amr_twin.experiments.navigation.generated import episodes as hall_episodes

        return hall_episodes(cfg, world, n, seed, people)
    costmap = make_costmap(true_map(cfg, world), robot_footprint(cfg), cfg.navigation)
    planner = GlobalPlanner(costmap)
    free = free_cells(costmap)
    out = []
    for i in range(n):
        rng = np.random.default_rng([seed, i])
        scenario = str(rng.choice(SCENARIOS, p=SHARES))
        for _attempt in range(200):
            a, b = free[rng.integers(len(free))], free[rng.integers(len(free))]
            if not MIN_APART_M <= math.hypot(*(b - a)) <= MAX_APART_M:
                continue
            plan = planner.plan(a, b)
            if plan is None:
                continue
            start = (float(a[0]), float(a[1]), float(rng.uniform(-math.pi, math.pi)))
            goal = (float(b[0]), float(b[1]), float(rng.uniform(-math.pi, math.pi)))
            placed = (
                None
                if scenario == "clear"
                else place(rng, scenario, plan, costmap, start, goal, people)
            )
            if scenario != "clear" and placed is None:
                continue
            actor = placed if placed is not None and not isinstance(placed, Obstacle) else None
            out.append(
                Episode(
                    i, seed, start, goal, scenario, None if actor is not None else placed, actor
                )
            )
            break
        else:
            raise ValueError(
                f"episode {i}: no start/goal pair {MIN_APART_M:g}-{MAX_APART_M:g} m apart found in "
                f"world {world}"
            )
    return out


def run(
    cfg,
    world: str,
    n: int,
    *,
    seed: int = 0,
    maps: tuple = MAPS,
    slam_yaml: str | None = None,
    slam_stem=None,
    localisation: str = "ekf",
    controller: str = "mppi",
    firmware: str = "improved",
    jobs: int = 1,
    client=None,
    progress: bool = True,
    people: str = "walking",
) -> NavigationResult:
    """Every episode on every map (building the SLAM map at ``slam_stem`` first when ``slam_yaml``
    is None)."""
    import time

    from amr_twin.experiments.runner.executor import run_all
    from amr_twin.experiments.navigation.metrics import summary
    from amr_twin.experiments.navigation.map import build_slam_map
    from amr_twin.navigation.stack import load_static_map

    wall0, cpu0 = time.perf_counter(), time.process_time()
    slam = None
    if "slam" in maps:
        if slam_yaml is None:
            slam = build_slam_map(cfg, world, slam_stem, seed=seed, progress=progress)
            slam_yaml = slam["yaml"]
        else:
            slam = {"yaml": str(slam_yaml), "route": "given (--slam-map)"}
    eps = episodes(cfg, world, n, seed, people)
    items = [
        EpisodeRun(cfg, world, ep, kind, slam_yaml, localisation, controller, firmware)
        for ep in eps
        for kind in maps
    ]
    rows = [
        row
        for _item, row in run_all(
            timed_episode,
            items,
            jobs=jobs,
            client=client,
            description="navigation episodes",
            progress=progress,
        )
    ]
    rows.sort(key=lambda r: (r["index"], MAPS.index(r["map"])))
    static_maps = {
        kind: load_static_map(cfg, world, slam_yaml if kind == "slam" else None) for kind in maps
    }
    return NavigationResult(
        world=world,
        episodes=n,
        seed=seed,
        people=people,
        maps=list(maps),
        localisation=localisation,
        controller=controller,
        firmware=firmware,
        slam_map=slam,
        optimal=OPTIMAL,
        summary=summary(rows),
        rows=rows,
        static_maps=static_maps,
        jobs=jobs,
        wall_s=time.perf_counter() - wall0,
        cpu_s=time.process_time()
        - cpu0
        + sum(r["cpu_s"] for r in rows) * (jobs > 1 or client is not None),
    )


def run_halls(
    cfg,
    worlds: list[str],
    tuning: list[str],
    n: int,
    *,
    seed: int = 0,
    localisation: str = "ekf",
    controller: str = "mppi",
    firmware: str = "improved",
    jobs: int = 1,
    client=None,
    progress: bool = True,
    people: str = "walking",
) -> HallsResult:
    """``n`` episodes on the true map of each generated hall of ``worlds``, summed up for the
    ``tuning`` halls and for the others (held out) apart (:mod:`.generated`); each with a walking
    person also run without them, for the time the people cost (``people`` of each group's summary,
    ``rows_without_people``)."""
    import time

    from amr_twin.experiments.runner.executor import run_all
    from amr_twin.experiments.navigation.generated import (
        WITHOUT_PEOPLE,
        door_summary,
        people_penalty,
        without_people,
    )
    from amr_twin.experiments.navigation.metrics import summary
    from amr_twin.navigation.stack import true_map

    wall0, cpu0 = time.perf_counter(), time.process_time()
    items = [
        EpisodeRun(cfg, world, ep, "true", None, localisation, controller, firmware)
        for world in worlds
        for ep in episodes(cfg, world, n, seed, people)
    ]
    done = [
        row
        for _item, row in run_all(
            timed_episode,
            items + without_people(items),
            jobs=jobs,
            client=client,
            description="navigation episodes",
            progress=progress,
        )
    ]
    done.sort(key=lambda r: (worlds.index(r["world"]), r["index"]))
    rows = [r for r in done if r["scenario"] != WITHOUT_PEOPLE]
    bare = [r for r in done if r["scenario"] == WITHOUT_PEOPLE]
    groups = {
        "tuning": [w for w in worlds if w in tuning],
        "held_out": [w for w in worlds if w not in tuning],
    }
    summaries = {}
    for group, members in groups.items():
        sel = [r for r in rows if r["world"] in members]
        if sel:
            summaries[group] = {
                "worlds": members,
                "episodes": summary(sel),
                "doors": door_summary(sel),
                "people": people_penalty(sel, [r for r in bare if r["world"] in members]),
            }
    return HallsResult(
        worlds=worlds,
        groups=groups,
        episodes=n,
        seed=seed,
        people=people,
        maps=["true"],
        localisation=localisation,
        controller=controller,
        firmware=firmware,
        optimal=OPTIMAL,
        summary=summaries,
        by_world={w: door_summary([r for r in rows if r["world"] == w]) for w in worlds},
        rows=rows,
        rows_without_people=bare,
        static_maps={w: true_map(cfg, w) for w in worlds},
        jobs=jobs,
        wall_s=time.perf_counter() - wall0,
        cpu_s=time.process_time()
        - cpu0
        + sum(r["cpu_s"] for r in done) * (jobs > 1 or client is not None),
    )
