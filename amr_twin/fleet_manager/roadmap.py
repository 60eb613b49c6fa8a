"""A world's roadmap: the graph vehicles drive on, drawn from the occupancy map the navigation stack
builds (:func:`amr_twin.navigation.stack.load_static_map`).

The free space's centre lines (:mod:`amr_twin.fleet_manager.skeleton`, cells where the robot turns
in place with ``margin_m`` to spare) become a networkx graph: the largest connected piece is kept,
chains through two-way points are joined, and each line between key points is cut into pieces of at
most ``spacing_m`` along it. Nodes are of three kinds: ``junction`` (three or more edges), ``end``
(one edge: a dead end, used as a dock) and ``aisle`` (on a line between them: in front of a rack
face). Each edge has its ``length_m`` (the straight distance between its nodes) and its
``width_m``, the free width across it (twice the least clearance along it). Node ids are ``n0``,
``n1``, ... in order of position (x, then y).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import networkx as nx
import numpy as np

from amr_twin.fleet_manager.skeleton import clearance_m, thin, trace

SPACING_M = 2.7
"""Longest edge between two nodes, m: one bay of the warehouse world's racks (uprights every
2.7 m)."""
MARGIN_M = 0.15
"""Clearance kept beyond the robot's circumscribed radius where the roadmap runs, m."""
SPUR_M = 1.5
"""Dead ends of the centre lines shorter than this are pruned, m."""
DEVIATION_M = 0.3
"""allowedDeviationXY of the roadmap's nodes in the orders, m."""


@dataclass
class Roadmap:
    """The graph (node attributes ``xy`` (m), ``kind``; edge attributes ``length_m``,
    ``width_m``) on map ``map_id``."""

    graph: nx.Graph
    map_id: str
    deviation_m: float = DEVIATION_M

    def xy(self, node: str) -> tuple[float, float]:
        return self.graph.nodes[node]["xy"]

    def nodes_of(self, kind: str) -> list[str]:
        """The nodes of ``kind`` (``junction``, ``end``, ``aisle``, ``home``), in id order."""
        return [n for n, k in self.graph.nodes(data="kind") if k == kind]

    def nearest_of(self, kind: str, x: float, y: float) -> str | None:
        """The node of ``kind`` nearest (x, y), or None."""
        nodes = self.nodes_of(kind)
        return min(nodes, key=lambda n: math.dist(self.xy(n), (x, y))) if nodes else None

    def nearest(self, x: float, y: float) -> tuple[str, float]:
        """The node nearest (x, y) and its distance, m."""
        best = min(self.graph.nodes, key=lambda n: math.dist(self.xy(n), (x, y)))
        return best, math.dist(self.xy(best), (x, y))

    def attach(self, name: str, x: float, y: float) -> str:
        """The node a vehicle standing at (x, y) starts from: the nearest node if within
        :attr:`deviation_m`, else a ``home`` node ``name`` there, joined to the nearest node."""
        node, dist = self.nearest(x, y)
        if dist <= self.deviation_m or node == name:
            return node
        self.graph.add_node(name, xy=(float(x), float(y)), kind="home")
        width = self.graph.nodes[node]["width_m"]
        self.graph.add_edge(name, node, length_m=dist, width_m=width)
        if self.graph.is_directed():
            self.graph.add_edge(node, name, length_m=dist, width_m=width)
        return name

    def route(self, start: str, goal: str, avoid=frozenset()) -> list[str] | None:
        """The shortest way from ``start`` to ``goal`` (networkx' Dijkstra on ``length_m``) not
        through the nodes of ``avoid`` (but the goal); None if there is none."""
        if start == goal:
            return [start]
        keep = [n for n in self.graph.nodes if n not in avoid or n in (start, goal)]
        try:
            return nx.dijkstra_path(self.graph.subgraph(keep), start, goal, weight="length_m")
        except nx.NetworkXNoPath:
            return None

    def length_m(self, path: list[str]) -> float:
        """The length of ``path`` (node ids) along its edges, m."""
        return sum(self.graph.edges[a, b]["length_m"] for a, b in zip(path, path[1:]))

    def position(self, node: str) -> dict:
        """The VDA 5050 nodePosition of ``node``."""
        x, y = self.xy(node)
        return {
            "x": round(x, 3),
            "y": round(y, 3),
            "mapId": self.map_id,
            "allowedDeviationXY": self.deviation_m,
        }


def world_roadmap(cfg, world: str, map_yaml: str | None = None) -> Roadmap:
    """The roadmap of ``world`` (or of the map_server map ``map_yaml``) for the robot of ``cfg``,
    on mapId the world's name (:func:`amr_twin.fleet.session.map_id`), with directed lanes where
    its corridors are wide enough (:func:`amr_twin.fleet_manager.lanes.lane_roadmap`)."""
    from amr_twin.fleet.session import map_id
    from amr_twin.fleet_manager.lanes import lane_roadmap
    from amr_twin.navigation.footprint import robot_footprint
    from amr_twin.navigation.stack import load_static_map

    static = load_static_map(cfg, world, map_yaml)
    radius = robot_footprint(cfg).circumscribed_radius_m
    return lane_roadmap(build_roadmap(static, map_id(world), radius), radius, MARGIN_M)


def build_roadmap(
    static,
    map_id: str,
    robot_radius_m: float,
    spacing_m: float = SPACING_M,
    margin_m: float = MARGIN_M,
) -> Roadmap:
    """The roadmap of ``static`` (a :class:`~amr_twin.navigation.static_map.StaticMap`) for a robot
    of circumscribed radius ``robot_radius_m`` (module docstring); ValueError if no line fits."""
    res, origin = static.resolution_m, np.asarray(static.origin_xy_m, float)
    clear = clearance_m(static.occupied | static.unknown, res)
    skel = trace(thin(clear >= robot_radius_m + margin_m), res, SPUR_M)
    lines = nx.MultiGraph()
    for k, key in enumerate(skel.keys):
        lines.add_node(k, xy=origin + (key[::-1] + 0.5) * res)
    for k, br in enumerate(skel.branches):
        xy = origin + (br.cells[:, ::-1] + 0.5) * res
        width = 2.0 * float(clear[br.cells[:, 0], br.cells[:, 1]].min())
        lines.add_edge(br.a, br.b, key=k, xy=xy, width_m=width, start=br.a)
    if lines.number_of_edges() == 0:
        raise ValueError(f"map {map_id!r}: no aisle wide enough for the robot")
    lines = lines.subgraph(max(nx.connected_components(lines), key=len)).copy()
    _join_two_way(lines)
    return Roadmap(_cut(lines, spacing_m), map_id)


def _join_two_way(lines: nx.MultiGraph) -> None:
    """Join the two lines through every key point with exactly two (a bend the tracing split).
    Each line's ``xy`` runs from its key point ``start``."""
    for node in [n for n in lines.nodes if lines.degree(n) == 2]:
        (u1, v1, d1), (u2, v2, d2) = lines.edges(node, data=True)
        a, b = (u1 if u1 != node else v1), (u2 if u2 != node else v2)
        if a == node or b == node:  # a loop through itself: leave it
            continue
        xa = d1["xy"] if d1["start"] == a else d1["xy"][::-1]  # a -> node
        xb = d2["xy"] if d2["start"] == node else d2["xy"][::-1]  # node -> b
        lines.remove_node(node)
        lines.add_edge(
            a, b, xy=np.vstack([xa, xb[1:]]), width_m=min(d1["width_m"], d2["width_m"]), start=a
        )


def _cut(lines: nx.MultiGraph, spacing_m: float) -> nx.Graph:
    """The roadmap graph: every line cut into equal pieces of at most ``spacing_m``."""
    points: list[tuple[tuple[float, float], str]] = []
    pieces: list[tuple[int, int, float]] = []
    index: dict = {}

    def node_at(xy, kind: str, key=None) -> int:
        if key is not None and key in index:
            return index[key]
        points.append(((round(float(xy[0]), 3), round(float(xy[1]), 3)), kind))
        if key is not None:
            index[key] = len(points) - 1
        return len(points) - 1

    for u, v, d in sorted(lines.edges(data=True), key=lambda e: tuple(e[2]["xy"][0])):
        xy, a = d["xy"], d["start"]
        b = v if a == u else u
        xy = np.vstack([lines.nodes[a]["xy"], xy[1:-1], lines.nodes[b]["xy"]])
        s = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(xy, axis=0).T))])
        parts = max(1, math.ceil(s[-1] / spacing_m))
        ids = [node_at(lines.nodes[a]["xy"], _kind(lines, a), a)]
        for i in range(1, parts):
            at = s[-1] * i / parts
            ids.append(node_at([np.interp(at, s, xy[:, 0]), np.interp(at, s, xy[:, 1])], "aisle"))
        ids.append(node_at(lines.nodes[b]["xy"], _kind(lines, b), b))
        pieces += [(u, v, d["width_m"]) for u, v in zip(ids, ids[1:]) if u != v]
    order = sorted(range(len(points)), key=lambda i: points[i][0])
    name = {i: f"n{j}" for j, i in enumerate(order)}
    graph = nx.Graph()
    for i in order:
        xy, kind = points[i]
        graph.add_node(name[i], xy=xy, kind=kind)
    for u, v, width in pieces:
        length = math.dist(points[u][0], points[v][0])
        graph.add_edge(name[u], name[v], length_m=round(length, 3), width_m=round(width, 3))
    for n in graph.nodes:
        graph.nodes[n]["width_m"] = min(w for _, _, w in graph.edges(n, data="width_m"))
    return graph


def _kind(lines: nx.MultiGraph, key) -> str:
    return "end" if lines.degree(key) == 1 else "junction"
