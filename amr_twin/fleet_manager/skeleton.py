"""The free space's centre lines on an occupancy map: where a robot fits, thinned to lines one cell
wide, traced into a graph of junctions, ends and the cell chains between them.

1. *Room*: the cells whose distance to the nearest obstacle (scipy's Euclidean distance transform)
   is at least ``clearance_m``, the robot's half width and a margin.
2. *Thinning*: Zhang and Suen's parallel thinning (Zhang, T. Y. and Suen, C. Y., "A fast parallel
   algorithm for thinning digital patterns", CACM 27(3), 1984) of the room to its skeleton.
3. *Tracing*: skeleton cells with one neighbour (8-connected) are ends, with three or more
   junctions (adjacent junction cells are one junction); the chains between them are the
   skeleton's branches, each a list of cells. Branches ending in an end cell shorter than
   ``spur_m`` are pruned (the stubs thinning leaves in corners and rack bays).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import ndimage

_OFFSETS = ((-1, 0), (-1, 1), (0, 1), (1, 1), (1, 0), (1, -1), (0, -1), (-1, -1))
"""The 8 neighbours P2..P9 of Zhang and Suen's paper, clockwise from north (row - 1)."""


def clearance_m(occupied: np.ndarray, resolution_m: float) -> np.ndarray:
    """Distance of each cell's centre to the nearest occupied cell or the map's border, m."""
    free = np.pad(~occupied, 1, constant_values=False)
    return ndimage.distance_transform_edt(free)[1:-1, 1:-1] * resolution_m


def thin(room: np.ndarray) -> np.ndarray:
    """Zhang and Suen's thinning of the boolean image ``room`` to lines one cell wide."""
    img = np.pad(room.astype(np.uint8), 1)
    while True:
        changed = False
        for step in (0, 1):
            p = [np.roll(np.roll(img, -dr, 0), -dc, 1) for dr, dc in _OFFSETS]
            b = sum(p)
            a = sum(((p[k] == 0) & (p[(k + 1) % 8] == 1)).astype(np.uint8) for k in range(8))
            p2, p4, p6, p8 = p[0], p[2], p[4], p[6]
            if step == 0:
                c1, c2 = p2 * p4 * p6, p4 * p6 * p8
            else:
                c1, c2 = p2 * p4 * p8, p2 * p6 * p8
            drop = (img == 1) & (b >= 2) & (b <= 6) & (a == 1) & (c1 == 0) & (c2 == 0)
            if drop.any():
                img[drop], changed = 0, True
        if not changed:
            return img[1:-1, 1:-1].astype(bool)


@dataclass(frozen=True)
class Branch:
    """A chain of skeleton cells ``(n, 2)`` (row, col) from key point ``a`` to key point ``b``
    (indices into :attr:`Skeleton.keys`), both ends' cells included."""

    a: int
    b: int
    cells: np.ndarray


@dataclass(frozen=True)
class Skeleton:
    """Key points (junctions and ends: cell (row, col) of each, and its degree) and the branches."""

    keys: np.ndarray
    degree: np.ndarray
    branches: tuple[Branch, ...]


def _neighbours(skel: np.ndarray, r: int, c: int) -> list[tuple[int, int]]:
    rows, cols = skel.shape
    return [
        (r + dr, c + dc)
        for dr, dc in _OFFSETS
        if 0 <= r + dr < rows and 0 <= c + dc < cols and skel[r + dr, c + dc]
    ]


def trace(skel: np.ndarray, resolution_m: float, spur_m: float) -> Skeleton:
    """The graph of the skeleton image ``skel`` (step 3 of the module docstring)."""
    skel = skel.copy()
    while True:
        keys, label, branches = _trace_once(skel)
        spurs = [
            br
            for br in branches
            if _length_cells(br.cells) * resolution_m < spur_m
            and min(_count(branches, br.a), _count(branches, br.b)) == 1
            and max(_count(branches, br.a), _count(branches, br.b)) >= 3
        ]
        if not spurs:
            break
        for br in spurs:  # the cells of the spur but its junction's
            for r, c in br.cells:
                if label[r, c] == 0 or _count(branches, label[r, c] - 1) == 1:
                    skel[r, c] = False
        skel = thin(skel)
    degree = np.array([_count(branches, k) for k in range(len(keys))], int)
    return Skeleton(np.array(keys, int).reshape(-1, 2), degree, tuple(branches))


def _count(branches: list[Branch], key: int) -> int:
    return sum((br.a == key) + (br.b == key) for br in branches)


def _length_cells(cells: np.ndarray) -> float:
    return float(np.hypot(*np.diff(cells, axis=0).T).sum()) if len(cells) > 1 else 0.0


def _trace_once(skel: np.ndarray) -> tuple[list, np.ndarray, list[Branch]]:
    """Key points (centre cells of the junction clusters and ends), their label image (key + 1 at
    each cluster's cells, 0 elsewhere) and the branches between them."""
    count = ndimage.convolve(skel.astype(int), np.ones((3, 3), int), mode="constant") - 1
    key_cells = skel & (count != 2)
    label, n = ndimage.label(key_cells, structure=np.ones((3, 3), int))
    keys = []
    for k in range(1, n + 1):
        rc = np.argwhere(label == k)
        keys.append(tuple(rc[np.argmin(((rc - rc.mean(0)) ** 2).sum(1))]))
    branches, seen = [], np.zeros_like(skel)
    for k in range(1, n + 1):
        for r, c in np.argwhere(label == k):
            for nb in _neighbours(skel, r, c):
                if label[nb] == k or seen[nb]:
                    continue
                path, prev, cur = [(r, c)], (r, c), nb
                while label[cur] == 0:
                    seen[cur] = True
                    path.append(cur)
                    nxt = [q for q in _neighbours(skel, *cur) if q != prev and not seen[q]]
                    nxt = [q for q in nxt if q not in path]
                    if not nxt:
                        break
                    prev, cur = cur, nxt[0]
                if label[cur] == 0:
                    continue  # a loose end (a ring without key points): no branch
                if label[cur] == k and len(path) < 3:
                    continue  # back into its own cluster
                path.append(cur)
                branches.append(Branch(k - 1, int(label[cur]) - 1, np.array(path, int)))
    return keys, label, _unique(branches)


def _unique(branches: list[Branch]) -> list[Branch]:
    """Each branch once (tracing from both ends finds a branch between two clusters twice when its
    inner cells are all neighbours of a cluster)."""
    out, seen = [], set()
    for br in branches:
        ident = frozenset({tuple(br.cells[0]), tuple(br.cells[-1])}) | {len(br.cells)}
        if ident not in seen:
            seen.add(ident)
            out.append(br)
    return out
