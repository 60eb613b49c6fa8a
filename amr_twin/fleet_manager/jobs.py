"""Transport jobs and who gets them: a seeded stream of jobs (pick at a rack face, drop at a dock,
a payload drawn from a range) and the nearest idle vehicle for each.

Rack faces are the roadmap's ``aisle`` nodes, docks its ``end`` nodes (dead ends; its junctions when
it has none). The nearest vehicle is the one with the shortest way to the pick node on the roadmap
(networkx' Dijkstra on the edges' lengths), ties broken by serial number.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import networkx as nx
import numpy as np

PAYLOAD_KG = (5.0, 50.0)
"""The payload range of a job stream, kg: up to the factsheet's maxLoadMass (50 kg)."""


@dataclass(frozen=True)
class Job:
    """Carry ``payload_kg`` from node ``pick`` to node ``drop``."""

    job_id: str
    pick: str
    drop: str
    payload_kg: float


def job_stream(
    roadmap, count: int, seed: int, payload_kg: tuple = PAYLOAD_KG, exclude=frozenset()
) -> list[Job]:
    """``count`` jobs drawn with numpy's generator seeded ``seed``: a pick node among the rack
    faces, a drop node among the docks (not in ``exclude``: the charging nodes), a payload uniform
    in ``payload_kg`` (rounded to 0.1 kg)."""
    lo, hi = payload_kg
    if not (math.isfinite(lo) and math.isfinite(hi) and 0 <= lo <= hi):
        raise ValueError(f"payload range {payload_kg}: expected 0 <= LOW <= HIGH kg")
    faces = roadmap.nodes_of("aisle")
    docks = [n for n in roadmap.nodes_of("end") or roadmap.nodes_of("junction") if n not in exclude]
    if not faces or not docks:
        raise ValueError(f"map {roadmap.map_id!r}: no rack face or no dock on its roadmap")
    rng = np.random.default_rng(seed)
    return [
        Job(
            f"job-{k + 1}",
            faces[int(rng.integers(len(faces)))],
            docks[int(rng.integers(len(docks)))],
            round(float(rng.uniform(lo, hi)), 1),
        )
        for k in range(count)
    ]


def nearest_vehicle(graph: nx.Graph, idle: dict[str, str], node: str) -> str | None:
    """Of the ``idle`` vehicles (serial number -> the node it stands at), the one with the shortest
    way to ``node`` (along the lanes of a directed graph); None if none can reach it."""
    if not idle:
        return None
    back = graph.reverse(copy=False) if graph.is_directed() else graph
    dist = nx.single_source_dijkstra_path_length(back, node, weight="length_m")
    reach = [(dist[n], s) for s, n in idle.items() if n in dist]
    return min(reach)[1] if reach else None
