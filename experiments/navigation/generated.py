"""The navigation experiment on generated halls (``generated:SEED``): door trips, the doorways'
clearance.

:func:`episodes` draws episode ``i`` from ``default_rng([seed, hall seed, i])``: half of them
(``DOOR_SHARE``) are **door trips**, the start on one side of the inner wall and the goal on the
other (which side first drawn too), the others keep to one side (the rack section or the room);
start and goal ``MIN_APART_M`` to ``MAX_APART_M`` apart, ``FREE_CLEARANCE_M`` from any obstacle,
outside the cage, joined by the planner on the true map. The scenario is drawn as in the hand-made
worlds (:mod:`.episodes`: clear, a person, a pallet jack), or ``clear`` only (``people`` ``none``);
a person or jack stands on the way where it is 0.9-1.6 m from the map's obstacles (aisles of
uneven width), never in a doorway. ``crossing`` people walk across without giving way.

:func:`door_metrics` measures each doorway the robot drove through: the least clearance of the
true footprint (10 ms poses) to each jamb (the inner wall's pieces south and north of it) while
its centre is within ``DOOR_ZONE_M`` of the doorway. :func:`without_people` gives the episodes with
a walking person again without them, :func:`people_penalty` the extra time to the goal the people
cost. :func:`write_world` writes a hall as MJCF and its true map as a map_server YAML + PGM.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from dataclasses import replace

from amr_twin.experiments.navigation.episodes import SCENARIOS, SHARES, Episode, free_cells, place
from amr_twin.model.worlds import Obstacle

DOOR_SHARE = 0.5
MIN_APART_M, MAX_APART_M = 5.0, 30.0
WEST_SHARE = 0.6
"""Share of the one-side episodes in the rack section (the rest in the room behind the inner
wall)."""
PLACE_CLEAR_M = (0.9, 1.6)
DOOR_ZONE_M = 0.8
"""A pose is in a doorway while its centre is this close to the wall's centre line and to the
opening (m)."""
WITHOUT_PEOPLE = "person_left_out"
"""The scenario of an episode with a walking person run again without them (the reference of
:func:`people_penalty`)."""


def _crossed(hall, xy: np.ndarray) -> tuple[str, ...]:
    """The doorways a path (n, 2) goes through."""
    out = []
    for d in hall.doors:
        near = (np.abs(xy[:, 1] - d.y_m) <= d.width_m / 2) & (
            np.abs(xy[:, 0] - d.x_m) <= DOOR_ZONE_M
        )
        side = np.sign(xy[near, 0] - d.x_m)
        if near.any() and side.min() < 0 < side.max():
            out.append(d.name)
    return tuple(out)


def _in_cage(hall, xy: np.ndarray) -> np.ndarray:
    inside = np.zeros(len(xy), bool)
    for x0, y0, x1, y1 in hall.cages:
        inside |= (xy[:, 0] > x0) & (xy[:, 0] < x1) & (xy[:, 1] > y0) & (xy[:, 1] < y1)
    return inside


def _passable(cfg, world: str, obstacle: Obstacle, start, goal) -> bool:
    """Whether a path of the robot's inscribed disc joins start and goal past ``obstacle`` (the
    metrics' optimal length is finite): a jack must not close the only doorway or the dead end."""
    from amr_twin.experiments.navigation.optimal import VisibilityGraph
    from amr_twin.model.generated_world import hall as drawn
    from amr_twin.model.world_geometry import Footprints
    from amr_twin.navigation.footprint import robot_footprint
    from amr_twin.navigation.stack import robot_top_m

    boxes = [b for b in drawn(world).boxes if b.centre_m[2] - b.half_m[2] <= robot_top_m(cfg)]
    o = obstacle
    centre = np.array([b.centre_m[:2] for b in boxes] + [[o.x_m, o.y_m]])
    half = np.array([b.half_m[:2] for b in boxes] + [[o.size_m[0] / 2, o.size_m[1] / 2]])
    fp = Footprints(
        centre,
        half,
        np.r_[np.zeros(len(boxes)), o.yaw_rad],
        tuple(b.name for b in boxes) + (o.name,),
    )
    lo, hi = centre.min(0) - 2.0, centre.max(0) + 2.0
    graph = VisibilityGraph(
        fp, robot_footprint(cfg).inscribed_radius_m, (lo[0], lo[1], hi[0], hi[1])
    )
    return math.isfinite(graph.length_m(start[:2], goal[:2]))


def episodes(cfg, world: str, n: int, seed: int = 0, people: str = "walking") -> list[Episode]:
    """``n`` episodes of the generated hall ``world`` (module docstring)."""
    from amr_twin.model.generated_world import hall as drawn
    from amr_twin.navigation.footprint import robot_footprint
    from amr_twin.navigation.planner import GlobalPlanner
    from amr_twin.navigation.stack import make_costmap, true_map

    hall = drawn(world)
    costmap = make_costmap(true_map(cfg, world), robot_footprint(cfg), cfg.navigation)
    planner = GlobalPlanner(costmap)
    free = free_cells(costmap)
    free = free[~_in_cage(hall, free)]
    sides = {"west": free[free[:, 0] < hall.west_x1_m], "east": free[free[:, 0] > hall.east_x0_m]}
    out = []
    for i in range(n):
        rng = np.random.default_rng([seed, hall.seed, i])
        door_trip = bool(rng.random() < DOOR_SHARE)
        scenario = "clear" if people == "none" else str(rng.choice(SCENARIOS, p=SHARES))
        for _attempt in range(300):
            if door_trip:
                first = str(rng.choice(["west", "east"]))
                ends = (first, "east" if first == "west" else "west")
            else:
                side = "west" if rng.random() < WEST_SHARE else "east"
                ends = (side, side)
            a, b = (sides[e][rng.integers(len(sides[e]))] for e in ends)
            if not MIN_APART_M <= math.hypot(*(b - a)) <= MAX_APART_M:
                continue
            plan = planner.plan(a, b)
            if plan is None:
                continue
            doors = _crossed(hall, plan.xy_m)
            if door_trip != bool(doors):
                continue
            start = (float(a[0]), float(a[1]), float(rng.uniform(-math.pi, math.pi)))
            goal = (float(b[0]), float(b[1]), float(rng.uniform(-math.pi, math.pi)))
            placed = (
                None
                if scenario == "clear"
                else place(rng, scenario, plan, costmap, start, goal, people, PLACE_CLEAR_M)
            )
            if scenario != "clear" and placed is None:
                continue
            if isinstance(placed, Obstacle) and not _passable(cfg, world, placed, start, goal):
                continue
            actor = placed if placed is not None and not isinstance(placed, Obstacle) else None
            out.append(
                Episode(
                    i,
                    seed,
                    start,
                    goal,
                    scenario,
                    None if actor is not None else placed,
                    actor,
                    doors,
                )
            )
            break
        else:
            raise ValueError(
                f"episode {i}: no {'door trip' if door_trip else 'start/goal pair'} "
                f"{MIN_APART_M:g}-{MAX_APART_M:g} m apart found in world {world}"
            )
    return out


def door_metrics(cfg, world: str, episode: Episode, run) -> dict:
    """``door_trip``, the doorways crossed by the robot (``doors_crossed``) and, for each, the least
    clearance of the true footprint to its south and north jambs, m (``door_clearance``)."""
    from amr_twin.experiments.navigation.metrics import footprint_clearance_m
    from amr_twin.model.generated_world import hall as drawn
    from amr_twin.model.world_geometry import Footprints
    from amr_twin.navigation.footprint import robot_footprint

    hall = drawn(world)
    footprint = robot_footprint(cfg)
    boxes = {b.name: b for b in hall.boxes}
    pose = run.pose_true
    crossed = _crossed(hall, pose[:, :2])
    clearance = {}
    for d in hall.doors:
        if d.name not in crossed:
            continue
        near = (np.abs(pose[:, 0] - d.x_m) <= DOOR_ZONE_M) & (
            np.abs(pose[:, 1] - d.y_m) <= d.width_m / 2 + DOOR_ZONE_M
        )
        sides = {}
        for side, jamb in zip(("south_m", "north_m"), d.jambs):
            b = boxes[jamb]
            fp = Footprints(
                np.array([b.centre_m[:2]]), np.array([b.half_m[:2]]), np.zeros(1), (jamb,)
            )
            sides[side] = float(footprint_clearance_m(pose[near], footprint, fp).min())
        clearance[d.name] = {"width_m": d.width_m, **sides}
    return {
        "door_trip": bool(episode.doors),
        "doors_planned": list(episode.doors),
        "doors_crossed": list(crossed),
        "door_clearance": clearance,
    }


def without_people(items: list) -> list:
    """The items (``EpisodeRun``) of ``items`` whose episode has a walking person, that person left
    out (scenario ``WITHOUT_PEOPLE``): the same start, goal, hall and seeds."""
    return [
        replace(it, episode=replace(it.episode, actor=None, scenario=WITHOUT_PEOPLE))
        for it in items
        if it.episode.actor is not None
    ]


def people_penalty(rows: list[dict], bare: list[dict]) -> dict:
    """The people's cost in time: each episode of ``rows`` with a walking person against its run
    without them in ``bare`` (matched by hall and index), both reached: ``pairs``, median and worst
    extra seconds to the goal, and each pair's ``(world, index, extra_s)``; the person episodes,
    their successes, the episodes in which the robot touched a person
    (``person_contact_episodes``)."""
    ref = {(r["world"], r["index"]): r for r in bare}
    people = [r for r in rows if r.get("actor")]
    pairs = [
        (r["world"], r["index"], r["time_s"] - ref[(r["world"], r["index"])]["time_s"])
        for r in people
        if (r["world"], r["index"]) in ref
        and r["success"]
        and ref[(r["world"], r["index"])]["success"]
    ]
    extra = [e for _w, _i, e in pairs]
    return {
        "person_episodes": len(people),
        "person_success": int(sum(r["success"] for r in people)),
        "person_contact_episodes": int(
            sum(any(n.startswith("person") for n in r["collided_with"]) for r in rows)
        ),
        "without_people_success": int(sum(r["success"] for r in bare)),
        "pairs": len(pairs),
        "extra_s_median": float(np.median(extra)) if extra else None,
        "extra_s_max": max(extra) if extra else None,
        "extra_s": [[w, i, e] for w, i, e in pairs],
    }


def door_summary(rows: list[dict]) -> dict:
    """Door trips against the others: episodes, success, collisions, the least jamb clearance, true
    final error."""
    out = {}
    for group, sel in (
        ("door_trips", [r for r in rows if r.get("door_trip")]),
        ("other", [r for r in rows if not r.get("door_trip")]),
    ):
        if not sel:
            continue
        gaps = [
            min(c["south_m"], c["north_m"])
            for r in sel
            for c in r.get("door_clearance", {}).values()
        ]
        errors = [r["final_error_true_m"] for r in sel if r.get("final_error_true_m") is not None]
        out[group] = {
            "episodes": len(sel),
            "success": int(sum(r["success"] for r in sel)),
            "collisions": int(sum(r["collisions"] for r in sel)),
            "door_passages": len(gaps),
            "door_clearance_min_m": min(gaps) if gaps else None,
            "door_clearance_median_m": float(np.median(gaps)) if gaps else None,
            "final_error_true_m_median": float(np.median(errors)) if errors else None,
            "final_error_true_m_max": max(errors) if errors else None,
        }
    return out


def write_world(cfg, world: str, folder: Path) -> list[Path]:
    """Write the hall ``world`` as ``<stem>.xml`` (MJCF) and its true map as ``<stem>.yaml`` +
    ``<stem>.pgm`` (map_server: 0 occupied, 254 free, origin its lower-left corner) in ``folder``;
    the paths."""
    import yaml

    from amr_twin.model.generated_world import mjcf, parse
    from amr_twin.model.pgm import write_pgm
    from amr_twin.navigation.stack import true_map
    from amr_twin.base.atomic_file import replacing, write_text

    seed, door = parse(world)
    stem = f"generated_{seed}" + ("" if door is None else f"_door{door:g}")
    sm = true_map(cfg, world)
    write_text(folder / f"{stem}.xml", mjcf(world))
    with replacing(folder / f"{stem}.pgm") as tmp:
        write_pgm(tmp, np.where(sm.occupied, 0, 254).astype(np.uint8)[::-1])
    meta = {
        "image": f"{stem}.pgm",
        "resolution": sm.resolution_m,
        "origin": [float(sm.origin_xy_m[0]), float(sm.origin_xy_m[1]), 0.0],
        "occupied_thresh": 0.65,
        "free_thresh": 0.196,
        "negate": 0,
        "mode": "trinary",
    }
    write_text(folder / f"{stem}.yaml", yaml.safe_dump(meta, sort_keys=True))
    return [folder / f"{stem}.{ext}" for ext in ("xml", "yaml", "pgm")]
