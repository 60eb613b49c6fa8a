"""The optimal path length of an episode: the shortest path of the robot's centre in a visibility
graph.

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
TOLERANCE_M = 1e-3


class VisibilityGraph:
    """The free space of ``boxes`` (:class:`~amr_twin.model.world_geometry.Footprints`) for a disc
    of ``radius_m``."""

    def __init__(self, boxes, radius_m: float, bounds_xy_m: tuple[float, float, float, float]):
        polys = []
        for (cx, cy), (hx, hy), a in zip(boxes.centre_xy_m, boxes.half_xy_m, boxes.yaw_rad):
            c, s = math.cos(a), math.sin(a)
            corners = [
                (cx + c * x - s * y, cy + s * x + c * y)
                for x, y in ((-hx, -hy), (hx, -hy), (hx, hy), (-hx, hy))
            ]
            polys.append(shapely.Polygon(corners))
        grown = shapely.union_all([p.buffer(radius_m, quad_segs=QUAD_SEGS) for p in polys])
        self.free = shapely.box(*bounds_xy_m).difference(grown)
        # the segments are checked against obstacles grown 1 mm less: a segment tangent to a corner
        # touches it at a vertex, and rounding would otherwise put it a hair inside
        self._room = shapely.box(*bounds_xy_m).difference(
            shapely.union_all(
                [p.buffer(radius_m - TOLERANCE_M, quad_segs=QUAD_SEGS) for p in polys]
            )
        )
        shapely.prepare(self._room)

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
        comp = shapely.orient_polygons(
            comp
        )  # exterior counter-clockwise, holes clockwise: free space on the left
        verts = []
        for ring in [comp.exterior, *comp.interiors]:
            v = np.asarray(ring.coords)[:-1]
            e_in, e_out = v - np.roll(v, 1, axis=0), np.roll(v, -1, axis=0) - v
            turn = e_in[:, 0] * e_out[:, 1] - e_in[:, 1] * e_out[:, 0]
            verts.append(
                v[turn < 0]
            )  # a shortest path bends only where the boundary turns into the free space
        verts = np.vstack(verts)
        pts = np.vstack(
            [np.asarray(start_xy, float)[None], np.asarray(goal_xy, float)[None], verts]
        )
        n = len(pts)
        i, j = np.triu_indices(n, 1)
        a, b = pts[i], pts[j]
        d = np.hypot(*(b - a).T)
        ok = shapely.covers(self._room, shapely.linestrings(np.stack([a, b], axis=1)))
        graph = csr_matrix((d[ok], (i[ok], j[ok])), shape=(n, n))
        return float(dijkstra(graph, directed=False, indices=0)[1])
