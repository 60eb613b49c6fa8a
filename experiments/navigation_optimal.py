"""The optimal path length of an episode: the shortest path of the robot's centre in a visibility graph.

The free space is the world's floor minus every obstacle of the robot's height range (the true
world, unmapped obstacles included), each grown by the footprint's inscribed radius (shapely,
round joins drawn with chords inside the true circle). The shortest path from start to goal
passes through vertices of that free space (a visibility graph, Lozano-Perez and Wesley 1979):
nodes are the vertices of the free-space boundary and the two ends, edges the segments that stay
in the free space, Dijkstra finds the shortest (scipy.sparse.csgraph). No collision-free path of
the centre of a robot with that inscribed radius is shorter, and a rectangular robot needs at
least as much room: the figure is a lower bound of any path the robot can drive, so
travelled / optimal is not flattered.
"""

from __future__ import annotations

import math

import numpy as np
import shapely
from scipy.sparse import csr_matrix
from scipy.sparse.csgraph import dijkstra

QUAD_SEGS = 3


class VisibilityGraph:
    """The free space of ``boxes`` (:class:`~amr_twin.navigation.static_map.Boxes`) for a disc of ``radius_m``."""

    def __init__(self, boxes, radius_m: float, bounds_xy_m: tuple[float, float, float, float]):
        polys = []
        for (cx, cy), (hx, hy), a in zip(boxes.centre_xy_m, boxes.half_xy_m, boxes.yaw_rad):
            c, s = math.cos(a), math.sin(a)
            corners = [(cx + c * x - s * y, cy + s * x + c * y) for x, y in ((-hx, -hy), (hx, -hy), (hx, hy), (-hx, hy))]
            polys.append(shapely.Polygon(corners))
        grown = shapely.union_all([p.buffer(radius_m, quad_segs=QUAD_SEGS) for p in polys])
        self.free = shapely.box(*bounds_xy_m).difference(grown)
        shapely.prepare(self.free)
        self._vertices = None

    def _component(self, xy):
        geoms = getattr(self.free, "geoms", [self.free])
        for g in geoms:
            if g.covers(shapely.Point(xy)):
                return g
        return None

    def length_m(self, start_xy, goal_xy) -> float:
        """Shortest path length from start to goal, m (inf when none)."""
        comp = self._component(start_xy)
        if comp is None or not comp.covers(shapely.Point(goal_xy)):
            return math.inf
        rings = [comp.exterior, *comp.interiors]
        verts = np.vstack([np.asarray(r.coords)[:-1] for r in rings])
        pts = np.vstack([np.asarray(start_xy, float)[None], np.asarray(goal_xy, float)[None], verts])
        n = len(pts)
        i, j = np.triu_indices(n, 1)
        # a vertex of the boundary is on it: check each segment shrunk by 1 mm at both ends
        a, b = pts[i], pts[j]
        d = np.hypot(*(b - a).T)
        u = (b - a) / np.maximum(d, 1e-12)[:, None]
        shrink = np.minimum(1e-3, 0.25 * d)[:, None]
        lines = shapely.linestrings(np.stack([a + u * shrink, b - u * shrink], axis=1))
        shapely.prepare(comp)
        ok = shapely.covers(comp, lines)
        graph = csr_matrix((d[ok], (i[ok], j[ok])), shape=(n, n))
        return float(dijkstra(graph, directed=False, indices=0)[1])
