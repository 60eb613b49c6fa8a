"""The 8-connected graph of the costmap's grid the global planner searches with scipy's Dijkstra.

Reasons and measurements: docs/explanation/navigation.md#amr_twinnavigationplanner."""

from __future__ import annotations

import math

import numpy as np
from scipy.sparse import csr_matrix
from scipy.sparse.csgraph import dijkstra


class GridGraph:
    """The 8-connected graph of a ``shape`` grid, both directions of every move, in CSR order: built
    once, its edge weights set per search (an infinite weight: no edge, as scipy's Dijkstra takes
    it)."""

    def __init__(self, shape: tuple[int, int]):
        h, wd = shape
        self.shape = shape
        idx = np.arange(h * wd).reshape(h, wd)
        a, b, length = [], [], []
        for dr, dc, step in (
            (0, 1, 1.0),
            (1, 0, 1.0),
            (1, 1, math.sqrt(2.0)),
            (1, -1, math.sqrt(2.0)),
        ):
            p = idx[: h - dr, max(-dc, 0) : wd - max(dc, 0)].ravel()
            q = idx[dr:, max(dc, 0) : wd + min(dc, 0)].ravel()
            a += [p, q]
            b += [q, p]
            length += [np.full(len(p), step)] * 2
        a, b, length = np.concatenate(a), np.concatenate(b), np.concatenate(length)
        order = np.argsort(a, kind="stable")
        self.a, self.b, self.length = a[order], b[order], length[order]
        self.indptr = np.concatenate([[0], np.cumsum(np.bincount(self.a, minlength=h * wd))])

    def shortest(
        self, w: np.ndarray, start: tuple[int, int], goal: tuple[int, int]
    ) -> np.ndarray | None:
        """Cells (N, 2) row, col of the cheapest path on cell weights ``w`` (inf: blocked), or None;
        a move costs its length times the mean of its two cells' weights."""
        flat = w.ravel()
        graph = csr_matrix(
            (self.length * 0.5 * (flat[self.a] + flat[self.b]), self.b, self.indptr),
            shape=(flat.size, flat.size),
        )
        s, g = np.ravel_multi_index(start, self.shape), np.ravel_multi_index(goal, self.shape)
        dist, pred = dijkstra(graph, directed=True, indices=s, return_predecessors=True)
        if not np.isfinite(dist[g]):
            return None
        chain = [g]
        while chain[-1] != s:
            chain.append(pred[chain[-1]])
        return np.column_stack(np.unravel_index(np.array(chain[::-1]), self.shape))
