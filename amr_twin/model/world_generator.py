"""Seeded warehouse halls for navigation on worlds the code has never seen.

:func:`generate` draws, from one seed, a hall of about 24 x 14 m (origin at its centre, +x east):

- a rack section in the west: three rack rows along x, 0.9-1.3 m deep, at uneven spacing
  (aisles 1.6-4.5 m), between a west cross aisle (2.0-2.8 m) and an east one (2.2-3.0 m);
- a dead-end aisle (7-10 m): one aisle between two rows filled from the west, open at its east end;
- an inner wall across the hall with one or two doorways (0.85-1.2 m drawn, or all
``door_width_m``);
- behind it, a room with a pillar field (0.3-0.5 m columns, 1.2 m or more apart from anything)
  and a closed cage in one of its corners (free inside, reached by nothing).

Every obstacle is a box standing on the floor, tall enough for the LiDAR's 0.45 m scan plane
(walls, uprights 2.5 m; pallets of goods 1.2 m fill each rack row's floor level, beams and braces at
the scan plane).
Same seed and width, same world (NumPy's ``default_rng``). :mod:`amr_twin.model.generated_world`
writes it as MJCF; docs/explanation/navigation.md describes it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

DOOR_WIDTH_RANGE_M = (0.85, 1.2)
"""Range the doorways' widths are drawn from, m (the issue's generated doors)."""
FORCED_DOOR_RANGE_M = (0.6, 2.0)
"""Range a forced door width may take, m (the robot is 0.53 m across its wheels)."""
WALL_T_M, WALL_H_M = 0.2, 2.5
RACK_H_M, BEAM_Z_M = 2.5, (0.45, 1.5)
PILLAR_GAP_M = 1.2
"""Least gap between a pillar and any other obstacle, m: room to pass, no pocket the robot cannot
reach."""


@dataclass(frozen=True)
class Box:
    """An axis-aligned box: ``centre_m`` (x, y, z), ``half_m`` (x, y, z), ``material`` (MJCF)."""

    name: str
    centre_m: tuple[float, float, float]
    half_m: tuple[float, float, float]
    material: str


@dataclass(frozen=True)
class Door:
    """A doorway in the inner wall at ``x_m`` (the wall's centre line), centred at ``y_m``,
    ``width_m`` clear between its jambs, the wall pieces ``jambs`` (south, north)."""

    name: str
    x_m: float
    y_m: float
    width_m: float
    jambs: tuple[str, str]


@dataclass(frozen=True)
class GeneratedWorld:
    """A drawn hall: ``boxes``, ``doors``, ``cages`` and ``dead_end`` as (x0, y0, x1, y1) m, the
    sides of the inner wall (``west_x1_m``: its west face, ``east_x0_m``: its east face), the
    default start (x_m, y_m, yaw_rad) and the UWB anchors (x, y) m."""

    seed: int
    size_m: tuple[float, float]
    boxes: tuple[Box, ...]
    doors: tuple[Door, ...]
    cages: tuple[tuple[float, float, float, float], ...]
    dead_end: tuple[float, float, float, float]
    west_x1_m: float
    east_x0_m: float
    start_xy_yaw: tuple[float, float, float]
    anchors_xy_m: tuple[tuple[float, float], ...]


def _r(v: float) -> float:
    return round(float(v), 3)


def _box(
    out: list,
    name: str,
    x0: float,
    y0: float,
    x1: float,
    y1: float,
    z0: float,
    z1: float,
    material: str,
):
    """A box by its faces, rounded to the millimetre (centre and half sizes then hold them
    exactly)."""
    lo, hi = (_r(x0), _r(y0), _r(z0)), (_r(x1), _r(y1), _r(z1))
    out.append(
        Box(
            name,
            tuple(round((a + b) / 2, 4) for a, b in zip(lo, hi)),
            tuple(round((b - a) / 2, 4) for a, b in zip(lo, hi)),
            material,
        )
    )


def _rack_row(out: list, name: str, x0: float, x1: float, y0: float, y1: float) -> None:
    """Uprights every bay on both faces, braces across the depth, beams along both faces, pallets of
    goods filling the floor level (no free cell inside a row)."""
    bays = max(1, math.ceil((x1 - x0) / 2.7))
    u = 0.05
    _box(out, f"{name}_goods", x0 + 2 * u, y0 + 2 * u, x1 - 2 * u, y1 - 2 * u, 0.0, 1.2, "goods")
    for i, x in enumerate(np.linspace(x0 + u, x1 - u, bays + 1)):
        for face, y in (("s", y0 + u), ("n", y1 - u)):
            _box(out, f"{name}_{face}u{i}", x - u, y - u, x + u, y + u, 0.0, RACK_H_M, "rack")
        _box(out, f"{name}_brace{i}", x - 0.03, y0 + 2 * u, x + 0.03, y1 - 2 * u, 0.4, 0.5, "rack")
    for z in BEAM_Z_M:
        for face, y in (("s", y0 + u), ("n", y1 - u)):
            _box(
                out,
                f"{name}_{face}beam{z:g}",
                x0,
                y - 0.04,
                x1,
                y + 0.04,
                z - 0.05,
                z + 0.05,
                "beam",
            )


def _aisles(rng, inner_m: float) -> np.ndarray:
    """Four uneven aisle widths (south side, two between rows, north side) summing to
    ``inner_m``."""
    while True:
        a = rng.uniform(1.6, 3.2, 4)
        k = int(rng.integers(4))
        a[k] = inner_m - (a.sum() - a[k])
        if 1.6 <= a[k] <= 4.5:
            return a


def _pillars(rng, x0, y0, x1, y1, keep_out) -> list[tuple[float, float, float]]:
    """Pillar centres and half sizes on a jittered grid of the room, each at least PILLAR_GAP_M from
    the room's walls, the rectangles of ``keep_out`` and each other."""
    half = float(rng.uniform(0.15, 0.25))
    step = rng.uniform(2.0, 2.8, 2)
    jitter = 0.3
    out = []
    for x in np.arange(x0 + PILLAR_GAP_M + half + jitter, x1 - PILLAR_GAP_M - half, step[0]):
        for y in np.arange(y0 + PILLAR_GAP_M + half + jitter, y1 - PILLAR_GAP_M - half, step[1]):
            px, py = x + rng.uniform(-jitter, jitter), y + rng.uniform(-jitter, jitter)
            m = PILLAR_GAP_M + half
            if not (x0 + m <= px <= x1 - m and y0 + m <= py <= y1 - m):
                continue
            if any(
                px > a - m and px < c + m and py > b - m and py < d + m for a, b, c, d in keep_out
            ):
                continue
            if any(max(abs(px - qx), abs(py - qy)) < m + h for qx, qy, h in out):
                continue
            out.append((_r(px), _r(py), half))
    return out


def generate(seed: int, door_width_m: float | None = None) -> GeneratedWorld:
    """The hall of ``seed`` (module docstring); ``door_width_m``: every doorway this wide (else
    drawn)."""
    rng = np.random.default_rng([7919, int(seed)])
    W, H = _r(rng.uniform(22.0, 26.0)), _r(rng.uniform(13.0, 15.0))
    hw, hh = W / 2, H / 2
    boxes: list[Box] = []
    t = WALL_T_M
    _box(boxes, "wall_north", -hw - t, hh, hw + t, hh + t, 0, WALL_H_M, "wall")
    _box(boxes, "wall_south", -hw - t, -hh - t, hw + t, -hh, 0, WALL_H_M, "wall")
    _box(boxes, "wall_west", -hw - t, -hh, -hw, hh, 0, WALL_H_M, "wall")
    _box(boxes, "wall_east", hw, -hh, hw + t, hh, 0, WALL_H_M, "wall")
    # the inner wall and its doorways
    room_w = rng.uniform(6.5, 8.5)
    xw1 = _r(hw - room_w)  # the inner wall's east face
    xw0 = _r(xw1 - t)
    n_doors = int(rng.integers(1, 3))
    widths = [
        _r(door_width_m) if door_width_m is not None else _r(rng.uniform(*DOOR_WIDTH_RANGE_M))
        for _ in range(n_doors)
    ]
    while True:
        ys = np.sort(rng.uniform(-hh + 1.8, hh - 1.8, n_doors))
        if n_doors == 1 or ys[1] - ys[0] >= 4.0:
            break
    doors, y_from = [], -hh
    for k, (y, w) in enumerate(zip(ys, widths)):
        y = _r(y)
        _box(boxes, f"inner_wall_{k}", xw0, y_from, xw1, y - w / 2, 0, WALL_H_M, "wall")
        _box(boxes, f"door{k}_lintel", xw0, y - w / 2, xw1, y + w / 2, 2.1, WALL_H_M, "wall")
        doors.append(
            Door(f"door{k}", _r((xw0 + xw1) / 2), y, w, (f"inner_wall_{k}", f"inner_wall_{k + 1}"))
        )
        y_from = y + w / 2
    _box(boxes, f"inner_wall_{n_doors}", xw0, y_from, xw1, hh, 0, WALL_H_M, "wall")
    # the rack section: three rows at uneven spacing, one aisle between them a dead end
    cw, ce = rng.uniform(2.0, 2.8), rng.uniform(2.2, 3.0)
    xa, xb = _r(-hw + cw), _r(xw0 - ce)
    depth = rng.uniform(0.9, 1.3, 3)
    aisle = _aisles(rng, H - depth.sum())
    faces, y = [], -hh
    for k in range(3):
        y += aisle[k]
        faces.append((_r(y), _r(y + depth[k])))
        _rack_row(boxes, f"rack{k}", xa, xb, *faces[-1])
        y += depth[k]
    gap = int(rng.integers(1, 3))  # the aisle between rows gap-1 and gap
    dead_len = min(rng.uniform(7.0, 10.0), xb - xa - 2.0)
    xd = _r(xb - dead_len)
    ya, yb = faces[gap - 1][1], faces[gap][0]
    _box(boxes, "dead_end_block", xa, ya, xd, yb, 0, RACK_H_M, "goods")
    # the room: a cage in a corner, pillars elsewhere, the doorways' approaches kept clear
    cx, cy = _r(rng.uniform(2.0, 3.0)), _r(rng.uniform(1.8, 2.8))
    north = bool(rng.integers(2))
    c0, c1 = (hh - cy, hh) if north else (-hh, -hh + cy)
    cage = (_r(hw - cx), _r(c0), hw, _r(c1))
    p = 0.03
    _box(boxes, "cage_west", cage[0], cage[1], cage[0] + 2 * p, cage[3], 0, 2.0, "cage")
    _box(boxes, "cage_east", cage[2] - 2 * p, cage[1], cage[2], cage[3], 0, 2.0, "cage")
    _box(
        boxes,
        "cage_south",
        cage[0] + 2 * p,
        cage[1],
        cage[2] - 2 * p,
        cage[1] + 2 * p,
        0,
        2.0,
        "cage",
    )
    _box(
        boxes,
        "cage_north",
        cage[0] + 2 * p,
        cage[3] - 2 * p,
        cage[2] - 2 * p,
        cage[3],
        0,
        2.0,
        "cage",
    )
    keep_out = [cage] + [
        (xw1, d.y_m - d.width_m / 2 - 1.0, xw1 + 1.8, d.y_m + d.width_m / 2 + 1.0) for d in doors
    ]
    for i, (px, py, h) in enumerate(_pillars(rng, xw1, -hh, hw, hh, keep_out)):
        _box(boxes, f"pillar{i}", px - h, py - h, px + h, py + h, 0, WALL_H_M, "pillar")
    inset = 0.5
    anchors = (
        (hw - inset, hh - inset),
        (0.0, hh - inset),
        (-hw + inset, hh - inset),
        (-hw + inset, -hh + inset),
        (0.0, -hh + inset),
        (hw - inset, -hh + inset),
    )
    return GeneratedWorld(
        int(seed),
        (W, H),
        tuple(boxes),
        tuple(doors),
        (cage,),
        (xd, ya, xb, yb),
        xw0,
        xw1,
        (_r(-hw + cw / 2), 0.0, 0.0),
        tuple((_r(x), _r(y)) for x, y in anchors),
    )
