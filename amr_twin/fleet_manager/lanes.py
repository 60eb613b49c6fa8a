"""Directed lanes on a roadmap (:mod:`amr_twin.fleet_manager.roadmap`): the networkx DiGraph the
fleet manager reserves node by node, so that robots follow each other in a lane.

- A corridor (a chain of nodes between junctions) wide enough for two robots side by side
  (``width_m`` at least twice the lane offset plus the robot's radius and margin) becomes two
  one-way lanes, right-hand traffic, each ``robot radius + gap / 2`` off the centre line, joined
  at the corridor's junctions (which stay single nodes); lane nodes are of kind ``lane`` (no rack
  face: no pick there). Where the corridor is wider still, each lane node gets a *lay-by* at the
  rack face (kind ``aisle``, ``bay`` true): a robot picks there off the through lane, and an idle
  one parks there.
- A narrow corridor with a rack block on one side and the outer wall on the other is made one way,
  the block on its right (a clockwise circulation round the block, as the two-lane corridors run),
  if every node stays reachable from every other; other narrow corridors and dead ends (docks)
  stay two-way (the traffic's corridor rule).

Edges carry ``length_m``, ``width_m`` and ``oneway``. A roadmap without a wide corridor is
returned as it was (an undirected graph).
"""

from __future__ import annotations

import math
from dataclasses import replace

import networkx as nx
import numpy as np

PASSING_GAP_M = 1.0
"""Free gap between the circumscribed circles of two robots passing in opposite lanes, m: a
manager setting, above the navigator's 0.25 m goal tolerance on each side and the EKF's errors."""


def chains(graph: nx.Graph) -> list[list[str]]:
    """The graph's chains: node lists from a key node (other than two edges) through nodes with two
    edges to the next key node, each once, in the order of the graph's edges."""
    out, seen = [], set()
    for u, v in graph.edges:
        if frozenset((u, v)) in seen:
            continue
        chain = [u, v]
        while graph.degree(chain[0]) == 2 and chain[0] != chain[-1]:
            chain.insert(0, next(n for n in graph.neighbors(chain[0]) if n != chain[1]))
        while graph.degree(chain[-1]) == 2 and chain[0] != chain[-1]:
            chain.append(next(n for n in graph.neighbors(chain[-1]) if n != chain[-2]))
        seen |= {frozenset(e) for e in zip(chain, chain[1:])}
        out.append(chain)
    return out


def lane_roadmap(roadmap, robot_radius_m: float, margin_m: float, gap_m: float = PASSING_GAP_M):
    """The :class:`~amr_twin.fleet_manager.roadmap.Roadmap` ``roadmap`` with lanes (module
    docstring) for a robot of circumscribed radius ``robot_radius_m`` keeping ``margin_m`` from
    obstacles, m."""
    g = roadmap.graph
    offset = robot_radius_m + gap_m / 2.0
    room = robot_radius_m + margin_m
    out = nx.DiGraph()
    wide = False
    narrow = []
    for chain in chains(g):
        width = min(g.edges[a, b]["width_m"] for a, b in zip(chain, chain[1:]))
        dead_end = g.degree(chain[0]) == 1 or g.degree(chain[-1]) == 1
        for n in (chain[0], chain[-1]):
            out.add_node(n, **g.nodes[n])
        if dead_end or len(chain) < 3 or width / 2.0 < offset + room:
            for n in chain[1:-1]:
                out.add_node(n, **g.nodes[n])
            for a, b in zip(chain, chain[1:]):
                _edge(out, a, b, g.edges[a, b]["width_m"], False)
                _edge(out, b, a, g.edges[a, b]["width_m"], False)
            if not dead_end:
                narrow.append(chain)
            continue
        wide = True
        bay = width / 2.0 - room
        layby = bay - offset >= 2.0 * room
        for suffix, way in (("a", chain), ("b", chain[::-1])):
            _lane(out, g, way, suffix, offset, bay if layby else None, width)
    if not wide:
        return roadmap
    _circulate(out, g, narrow)
    for n in out.nodes:
        widths = [w for *_e, w in out.in_edges(n, data="width_m")]
        out.nodes[n]["width_m"] = min(widths + [w for *_e, w in out.out_edges(n, data="width_m")])
    return replace(roadmap, graph=out)


def _edge(out: nx.DiGraph, a: str, b: str, width: float, oneway: bool) -> None:
    length = round(math.dist(out.nodes[a]["xy"], out.nodes[b]["xy"]), 3)
    out.add_edge(a, b, length_m=length, width_m=round(width, 3), oneway=oneway)


def _lane(out, g, way: list[str], suffix: str, offset: float, bay, width: float) -> None:
    """One lane along ``way`` (key node, inner nodes, key node), its inner nodes ``offset`` to the
    right of the way, with lay-bys ``bay`` to the right (None: none)."""
    names = [way[0]] + [f"{n}{suffix}" for n in way[1:-1]] + [way[-1]]
    for i in range(1, len(way) - 1):
        before, here, after = (np.asarray(g.nodes[n]["xy"]) for n in way[i - 1 : i + 2])
        t = (after - before) / np.linalg.norm(after - before)
        right = np.array([t[1], -t[0]])
        kind = "lane" if g.nodes[way[i]]["kind"] == "aisle" else g.nodes[way[i]]["kind"]
        xy = here + offset * right
        out.add_node(names[i], xy=(round(float(xy[0]), 3), round(float(xy[1]), 3)), kind=kind)
        if bay is not None:
            xy = here + bay * right
            xy = (round(float(xy[0]), 3), round(float(xy[1]), 3))
            out.add_node(f"{names[i]}p", xy=xy, kind="aisle", bay=True)
    for a, b in zip(names, names[1:]):
        _edge(out, a, b, width / 2.0, True)
        if bay is not None and a in out and f"{a}p" in out:
            _edge(out, a, f"{a}p", width / 2.0, True)
            _edge(out, f"{a}p", b, width / 2.0, True)


def _circulate(out: nx.DiGraph, g: nx.Graph, narrow: list[list[str]]) -> None:
    """Make each narrow corridor one way with the enclosed side (a block inside a cycle of ``g``)
    on its right, where the other side is open and every node stays reachable."""
    rings = [np.array([g.nodes[n]["xy"] for n in cycle]) for cycle in nx.cycle_basis(g)]

    def enclosed(p) -> bool:
        return any(_inside(ring, p) for ring in rings)

    for chain in narrow:
        k = (len(chain) - 1) // 2
        a, b = (np.asarray(g.nodes[n]["xy"]) for n in chain[k : k + 2])
        t = (b - a) / np.linalg.norm(b - a)
        side = np.array([t[1], -t[0]]) * (g.edges[chain[k], chain[k + 1]]["width_m"] / 2 + 0.3)
        mid = (a + b) / 2.0
        right, left = enclosed(mid + side), enclosed(mid - side)
        if right == left:
            continue
        way = chain if right else chain[::-1]
        against = list(zip(way[1:], way[:-1]))
        kept = [(u, v, dict(out.edges[u, v])) for u, v in against]
        out.remove_edges_from(against)
        if nx.is_strongly_connected(out):
            for u, v in zip(way, way[1:]):
                out.edges[u, v]["oneway"] = True
        else:
            out.add_edges_from(kept)


def _inside(ring: np.ndarray, p) -> bool:
    """Whether point ``p`` lies inside the polygon ``ring`` ((n, 2) corners; even-odd rule)."""
    x, y = p
    a, b = ring, np.roll(ring, -1, axis=0)
    cross = (a[:, 1] > y) != (b[:, 1] > y)
    with np.errstate(divide="ignore", invalid="ignore"):
        at = a[:, 0] + (y - a[:, 1]) * (b[:, 0] - a[:, 0]) / (b[:, 1] - a[:, 1])
    return bool(np.count_nonzero(cross & (x < at)) % 2)
