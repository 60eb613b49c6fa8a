"""Narrow passages on a plan: a door is driven through on its centre line, aligned before the robot
enters.

Where the robot cannot turn in place (its centre closer to an obstacle than the circumscribed radius
plus ``clearance_m``), a grid path may cross a door diagonally and 5 cm off its middle (the 0.1 m
cells). nav2's Smac planners check the oriented footprint along their paths; here the grid path is
corrected where it matters. Each run of such points that passes between obstacles on both sides is a
passage:

1. its *throat* is the run's point nearest an obstacle; the passage's *axis* crosses the throat
   where the passage is narrowest (of the lines through it, the one whose obstacles on either side
   are closest together, to 0.5 deg), through the middle between those obstacles;
2. the path follows that axis from where the robot can turn in place on one side (the centre
   ``circumscribed + clearance_m`` from any obstacle) plus ``lead_m`` to the same on the other,
   provided the footprint, oriented along the axis, keeps ``clearance_m`` (or what the passage
   allows) all along; else the path is left as it was.

:func:`split` returns the pieces of the path: those to shorten and the passages to keep straight.
"""

from __future__ import annotations

import math

import numpy as np

from amr_twin.navigation.costmap import Costmap
from amr_twin.navigation.footprint import Footprint
from amr_twin.navigation.kinematics import to_map

REACH_M = 1.5
"""How far from the throat the obstacles on either side are looked for, and the longest lead, m."""
STEP_M = 0.01


def footprint_clearance_m(costmap: Costmap, footprint: Footprint, poses: np.ndarray) -> np.ndarray:
    """Least distance field value (n,) over the footprint's outline at each pose (n, 3), m (0: on a
    lethal cell)."""
    outline = footprint.outline_xy_m(costmap.resolution_m)
    pts = to_map(np.asarray(poses, float).reshape(-1, 3), outline).reshape(-1, 2)
    return costmap.distance_at(pts).reshape(-1, len(outline)).min(1)


def _widths(costmap: Costmap, p: np.ndarray, angles: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Distances (A, 2) from ``p`` to the first lethal cell along each direction of ``angles`` (A,)
    and its opposite (inf: none within :data:`REACH_M`), and the directions (A, 2)."""
    dirs = np.column_stack([np.cos(angles), np.sin(angles)])
    s = np.arange(STEP_M, REACH_M + 1e-9, STEP_M)
    out = np.full((len(angles), 2), np.inf)
    for k, sign in enumerate((1.0, -1.0)):
        q = p + sign * s[None, :, None] * dirs[:, None, :]
        hit = costmap.distance_at(q.reshape(-1, 2)).reshape(len(angles), len(s)) <= 0.0
        out[hit.any(1), k] = s[hit.argmax(1)[hit.any(1)]]
    return out, dirs


def throat(costmap: Costmap, p: np.ndarray) -> tuple[np.ndarray, np.ndarray, float] | None:
    """The passage through ``p`` (step 1 of the module docstring): the middle (2,) of its narrowest
    line, the axis' direction (2,) and the width, m; None without obstacles on both sides within
    :data:`REACH_M`."""
    coarse = np.arange(0.0, math.pi, math.radians(5.0))
    w, _ = _widths(costmap, p, coarse)
    best = float(coarse[np.argmin(w.sum(1))])
    if not np.isfinite(w.sum(1).min()):
        return None
    fine = best + np.radians(np.arange(-5.0, 5.01, 0.5))
    w, dirs = _widths(costmap, p, fine)
    k = int(np.argmin(w.sum(1)))
    n = dirs[k]
    return p + 0.5 * (w[k, 0] - w[k, 1]) * n, np.array([-n[1], n[0]]), float(w[k].sum())


def _runs(flags: np.ndarray) -> list[tuple[int, int]]:
    """First and last index of each run of True."""
    edges = np.diff(np.concatenate([[0], flags.astype(np.int8), [0]]))
    return list(zip(np.flatnonzero(edges == 1), np.flatnonzero(edges == -1) - 1))


def _lead(costmap: Costmap, p: np.ndarray, u: np.ndarray, turn_m: float, lead_m: float) -> float:
    """How far along ``u`` from ``p`` the axis goes on: to where the centre is ``turn_m`` from
    obstacles, plus ``lead_m``, m (at most :data:`REACH_M`)."""
    s = np.arange(0.0, REACH_M + 1e-9, 0.05)
    free = np.flatnonzero(costmap.distance_at(p + s[:, None] * u) >= turn_m)
    return float(min(s[free[0]] + lead_m, REACH_M)) if len(free) else REACH_M


def split(
    costmap: Costmap, footprint: Footprint, xy: np.ndarray, clearance_m: float, lead_m: float
) -> list[tuple[bool, np.ndarray]]:
    """The grid path ``xy`` (N, 2) as pieces ``(fixed, points)``: a fixed piece is a passage's axis
    (two points, driven straight), the others are to be shortened; consecutive pieces share their
    end points."""
    turn_m = footprint.circumscribed_radius_m + clearance_m
    d = costmap.distance_at(xy)
    narrow = d < turn_m
    narrow[[0, -1]] = False
    pieces, start, head = [], 0, xy[0]
    for a, b in _runs(narrow):
        k = a + int(np.argmin(d[a : b + 1]))
        found = throat(costmap, xy[k])
        if found is None:
            continue
        c, u, width = found
        if width > 2.0 * turn_m:  # a wide gap: room to turn
            continue
        u = u if float(u @ (xy[min(b + 1, len(xy) - 1)] - xy[max(a - 1, 0)])) >= 0.0 else -u
        l_in, l_out = _lead(costmap, c, -u, turn_m, lead_m), _lead(costmap, c, u, turn_m, lead_m)
        along = (xy - c) @ u
        before = np.flatnonzero((np.arange(len(xy)) < a) & (along <= -l_in))
        after = np.flatnonzero((np.arange(len(xy)) > b) & (along >= l_out))
        i = int(before[-1]) if len(before) else -1
        j = int(after[0]) if len(after) else len(xy)
        e_in, e_out = c - l_in * u, c + l_out * u
        if i < start:  # the robot starts on the lead: the axis from its foot there
            i, e_in = start, c + min(float((head - c) @ u), 0.0) * u
        if j > len(xy) - 1:  # the goal lies on the lead: the axis to its foot there
            j, e_out = len(xy) - 1, c + max(float((xy[-1] - c) @ u), 0.0) * u
        n = max(
            2, int(math.ceil(float(np.hypot(*(e_out - e_in))) / (0.5 * costmap.resolution_m))) + 1
        )
        line = e_in + np.linspace(0.0, 1.0, n)[:, None] * (e_out - e_in)
        poses = np.column_stack([line, np.full(n, math.atan2(u[1], u[0]))])
        need = min(clearance_m, 0.5 * width - footprint.half_width_m - costmap.resolution_m)
        if (footprint_clearance_m(costmap, footprint, poses) < need).any():
            continue
        pieces += [
            (False, np.vstack([head, xy[start + 1 : i + 1], e_in])),
            (True, np.array([e_in, e_out])),
        ]
        head, start = e_out, j - 1  # the next piece: from the axis' end on
    pieces.append((False, np.vstack([head, xy[start + 1 :]])))
    return pieces
