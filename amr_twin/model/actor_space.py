"""Where actors may walk: the world's free space, checked along a path, and seeded random paths on
it.

An actor must not walk through the world: MuJoCo never makes a mocap body touch the world's
static geoms, so a path through a rack would go unseen. :func:`check_paths` refuses, before a
run, an actor whose footprint (:func:`~amr_twin.model.actors.footprint_half_m`, turned with its
heading) overlaps an obstacle anywhere along its path (poses every :data:`STEP_M` along the
segments and every :data:`STEP_RAD` of the turns at the corners: closer than any footprint is
long, so no obstacle slips between two poses), or leaves the floor. The obstacles
(:func:`obstacle_boxes`) are the bounding boxes of the world's static geoms (group 0, no joint,
not a mocap body) that stand between the floor and the actor's height (a person's ``height_m``,
a jack's ``handle_height_m``), walls, racks and loose pallets alike. Rectangles overlap by the
separating-axis test.

:func:`random_actors` draws actors on that free space from a seed: each a person (3 in 4) or a
pallet jack, a speed uniform in its kind's range, a loop of :data:`RANDOM_WAYPOINTS` waypoints
2-15 m apart whose whole path keeps :data:`RANDOM_CLEARANCE_M` from every obstacle, starting
clear of the robot. Same seed and world, same actors.

Part of the physics layer (``PHYSICS_LAYER``): places a freshly compiled world's bodies in a private
MjData (``mj_kinematics``) to read where its static geoms stand; no twin's state is read or written.
"""

from __future__ import annotations

import math

import numpy as np

from amr_twin.model.actor_paths import actor_path
from amr_twin.model.actors import KINDS, Actor, ActorError, body_name, footprint_half_m
from amr_twin.model.world_geometry import WORLD_GROUP, Footprints

PHYSICS_LAYER = True

STEP_M = 0.05
STEP_RAD = 0.05
RANDOM_WAYPOINTS = 4
RANDOM_CLEARANCE_M = 0.2
RANDOM_TRIES = 400
ROBOT_CLEAR_M = 1.0
"""A random actor's start keeps this much from the robot's footprint circle, m."""


def obstacle_boxes(model, z_top_m: float) -> Footprints:
    """Plan-view boxes (oriented) of the static world geoms that stand in (0, ``z_top_m``] m of
    height."""
    import mujoco

    data = mujoco.MjData(model)
    mujoco.mj_kinematics(model, data)
    names, centres, halves, yaws = [], [], [], []
    for g in range(model.ngeom):
        b = model.geom_bodyid[g]
        if (
            model.geom_group[g] != WORLD_GROUP
            or model.geom_type[g] == mujoco.mjtGeom.mjGEOM_PLANE
            or model.body_weldid[b] != 0
            or model.body_mocapid[b] >= 0
        ):
            continue
        R, box = data.geom_xmat[g].reshape(3, 3), model.geom_aabb[g]
        centre = data.geom_xpos[g] + R @ box[:3]
        half_z = np.abs(R[2]) @ box[3:]
        if not (centre[2] + half_z > 1e-6 and centre[2] - half_z < z_top_m):
            continue
        names.append(mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_GEOM, g) or f"geom {g}")
        centres.append(centre[:2])
        if abs(R[2, 2]) > 1 - 1e-9:  # upright: its box turned about z
            halves.append(box[3:5])
            yaws.append(math.atan2(R[1, 0], R[0, 0]))
        else:  # tilted: the plan-view extent of its box, axis-aligned
            halves.append([np.abs(R[0]) @ box[3:], np.abs(R[1]) @ box[3:]])
            yaws.append(0.0)
    return Footprints(
        np.array(centres, float).reshape(-1, 2),
        np.array(halves, float).reshape(-1, 2),
        np.array(yaws, float),
        tuple(names),
    )


def floor_bounds(model) -> tuple[float, float, float, float] | None:
    """``(x_min, x_max, y_min, y_max)`` of the world's finite floor planes, m; None for an infinite
    one or none."""
    import mujoco

    planes = [
        g
        for g in range(model.ngeom)
        if model.geom_type[g] == mujoco.mjtGeom.mjGEOM_PLANE
        and model.body_weldid[model.geom_bodyid[g]] == 0
    ]
    if not planes or any(model.geom_size[g][0] <= 0 or model.geom_size[g][1] <= 0 for g in planes):
        return None
    x = [model.geom_pos[g][0] + s * model.geom_size[g][0] for g in planes for s in (-1, 1)]
    y = [model.geom_pos[g][1] + s * model.geom_size[g][1] for g in planes for s in (-1, 1)]
    return min(x), max(x), min(y), max(y)


def path_poses(actor: Actor, cfg) -> np.ndarray:
    """Poses (P, 3) x_m, y_m, yaw_rad along ``actor``'s whole path (one pass, corners included)."""
    path = actor_path(actor, cfg)
    rows = path.phases
    ends = np.append(rows[1:, 0], path.period_s if path.period_s > 0 else rows[-1, 0])
    out = []
    for (t0, x0, y0, vx, vy, yaw0, rate), t1 in zip(rows, ends):
        d = t1 - t0
        n = max(1, int(math.ceil(d * max(math.hypot(vx, vy) / STEP_M, abs(rate) / STEP_RAD))))
        dt = np.linspace(0.0, d, n + 1)
        out.append(np.column_stack([x0 + dt * vx, y0 + dt * vy, yaw0 + dt * rate]))
    return np.vstack(out)


def overlapping(
    poses: np.ndarray,
    half_m: tuple[float, float],
    boxes: Footprints,
    margin_m: float = 0.0,
    chunk: int = 4096,
) -> np.ndarray:
    """Index (P,) of the first box each pose's footprint (half length, half width, grown by
    ``margin_m``) overlaps, -1 where none (separating-axis test of the two rectangles)."""
    out = np.full(len(poses), -1)
    if not len(boxes):
        return out
    ha0, ha1 = np.array(half_m, float) + margin_m
    hb0, hb1 = boxes.half_xy_m[:, 0], boxes.half_xy_m[:, 1]
    cb, sb = np.cos(boxes.yaw_rad), np.sin(boxes.yaw_rad)
    for i in range(0, len(poses), chunk):
        p = poses[i : i + chunk]
        ca, sa = np.cos(p[:, 2])[:, None], np.sin(p[:, 2])[:, None]
        tx, ty = (
            boxes.centre_xy_m[None, :, 0] - p[:, 0:1],
            boxes.centre_xy_m[None, :, 1] - p[:, 1:2],
        )  # (P, K)
        c = np.abs(
            ca * cb + sa * sb
        )  # |cos| and |sin| of the angle between the two rectangles' axes
        s = np.abs(sa * cb - ca * sb)
        sep = np.abs(tx * ca + ty * sa) > ha0 + c * hb0 + s * hb1  # along the footprint's axes
        sep |= np.abs(ty * ca - tx * sa) > ha1 + s * hb0 + c * hb1
        sep |= np.abs(tx * cb + ty * sb) > hb0 + c * ha0 + s * ha1  # along the box's
        sep |= np.abs(ty * cb - tx * sb) > hb1 + s * ha0 + c * ha1
        hit = ~sep
        out[i : i + chunk] = np.where(hit.any(1), hit.argmax(1), -1)
    return out


def _outside(poses: np.ndarray, half_m, bounds) -> np.ndarray:
    """(P,) whether a footprint corner leaves ``bounds`` (None: never)."""
    if bounds is None:
        return np.zeros(len(poses), bool)
    r = math.hypot(*half_m)  # a circle round the footprint: enough for a floor's edge
    x0, x1, y0, y1 = bounds
    return (
        (poses[:, 0] - r < x0)
        | (poses[:, 0] + r > x1)
        | (poses[:, 1] - r < y0)
        | (poses[:, 1] + r > y1)
    )


def _height_m(kind: str, cfg) -> float:
    return (
        cfg.actors.person.height_m if kind == "person" else cfg.actors.pallet_jack.handle_height_m
    )


def check_paths(model, actors: tuple[Actor, ...], cfg) -> None:
    """Raise :class:`~amr_twin.model.actors.ActorError` for an actor whose path leaves the world's
    free space."""
    bounds = floor_bounds(model)
    for i, actor in enumerate(actors):
        half = footprint_half_m(actor.kind, cfg)
        poses = path_poses(actor, cfg)
        boxes = obstacle_boxes(model, _height_m(actor.kind, cfg))
        hit = overlapping(poses, half, boxes)
        out = _outside(poses, half, bounds)
        bad = np.nonzero((hit >= 0) | out)[0]
        if len(bad):
            j = int(bad[0])
            x, y = poses[j, :2]
            what = f"runs into {boxes.names[hit[j]]}" if hit[j] >= 0 else "leaves the floor"
            raise ActorError(
                f"actor {i} ({body_name(i, actor)}): its path {what} near ({x:.2f}, {y:.2f}) m; "
                f"its "
                f"{2 * half[0]:.2f} x {2 * half[1]:.2f} m footprint must stay in the world's "
                f"free space"
            )


def random_actors(
    model,
    n: int,
    seed: int,
    cfg,
    robot_xy_m: tuple[float, float],
    kinds: tuple[str, ...] = KINDS,
    stop_within_m: float = 0.0,
) -> tuple[Actor, ...]:
    """``n`` actors drawn on ``model``'s free space from ``seed`` (module notes)."""
    if not all(k in KINDS for k in kinds) or not kinds:
        raise ActorError(f"random actors: kinds must be among {', '.join(KINDS)}")
    rng = np.random.default_rng([int(seed), 0xAC7025])
    floor = floor_bounds(model)
    out = []
    for i in range(int(n)):
        kind = kinds[0] if len(kinds) == 1 else ("person" if rng.random() < 0.75 else "pallet_jack")
        k = getattr(cfg.actors, kind)
        half = footprint_half_m(kind, cfg)
        boxes = obstacle_boxes(model, _height_m(kind, cfg))
        area = _area(boxes, floor, robot_xy_m)
        speed = float(rng.uniform(k.speed_min_m_s, k.speed_max_m_s))
        out.append(
            _draw(rng, kind, speed, half, boxes, floor, area, robot_xy_m, cfg, stop_within_m, i)
        )
    return tuple(out)


def _area(boxes: Footprints, floor, robot_xy_m) -> tuple[float, float, float, float]:
    if len(boxes):
        reach = np.abs(boxes.half_xy_m).max(1)[:, None]
        lo, hi = (boxes.centre_xy_m - reach).min(0), (boxes.centre_xy_m + reach).max(0)
        area = [lo[0], hi[0], lo[1], hi[1]]
    else:
        x, y = robot_xy_m
        area = [x - 10.0, x + 10.0, y - 10.0, y + 10.0]
    if floor is not None:
        area = [
            max(area[0], floor[0]),
            min(area[1], floor[1]),
            max(area[2], floor[2]),
            min(area[3], floor[3]),
        ]
    return tuple(float(v) for v in area)


def _clear(actor: Actor, half, boxes, floor, cfg) -> bool:
    poses = path_poses(actor, cfg)
    return not (
        (overlapping(poses, half, boxes, RANDOM_CLEARANCE_M) >= 0) | _outside(poses, half, floor)
    ).any()


def _draw(
    rng, kind, speed, half, boxes, floor, area, robot_xy_m, cfg, stop_within_m, index
) -> Actor:
    x0, x1, y0, y1 = area
    r_start = math.hypot(*half) + 0.45 + ROBOT_CLEAR_M  # the robot's footprint circle: about 0.4 m
    for _ in range(RANDOM_TRIES):
        first = (float(rng.uniform(x0, x1)), float(rng.uniform(y0, y1)))
        if math.dist(first, robot_xy_m) < r_start or not _clear(
            Actor(kind, (first,), speed), half, boxes, floor, cfg
        ):
            continue
        points = [first]
        for _ in range(RANDOM_TRIES):
            nxt = (float(rng.uniform(x0, x1)), float(rng.uniform(y0, y1)))
            if not 2.0 <= math.dist(nxt, points[-1]) <= 15.0:
                continue
            trial = points + [nxt]
            last = len(trial) == RANDOM_WAYPOINTS
            actor = Actor(kind, tuple(trial), speed, loop=last, stop_within_m=stop_within_m)
            if _clear(actor, half, boxes, floor, cfg):
                points = trial
                if last:
                    return actor
        # this start led nowhere: draw another
    raise ActorError(
        f"random actors: could not place actor {index} ({kind}) on the world's free space in "
        f"{RANDOM_TRIES} draws (a world too cluttered for its footprint?)"
    )
