"""Seeded order streams: transport jobs arriving over time (pick at a rack face, drop at a dock,
a payload drawn from a range).

Arrivals are a Poisson process of ``jobs_per_hour`` (exponential gaps); the pick node is drawn
among the roadmap's ``aisle`` nodes (rack faces), the drop node among its ``end`` nodes (docks,
its junctions when it has none) less the charging nodes, the payload uniform in the range,
rounded to 0.1 kg and at least 0.1 kg (a VDA 5050 pick needs a weight > 0). Numpy's generator
seeded ``[seed, 46]``: same seed, same stream.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from amr_twin.fleet_manager.jobs import Job

MIN_PAYLOAD_KG = 0.1
"""The lightest load drawn, kg: a pick's weight must be > 0."""


@dataclass(frozen=True)
class Order:
    """A transport ``job`` that arrives at ``arrival_s`` s of simulated time."""

    job: Job
    arrival_s: float


def order_stream(
    roadmap,
    payload_kg: tuple[float, float],
    jobs_per_hour: float,
    duration_s: float,
    seed: int,
    exclude=frozenset(),
) -> list[Order]:
    """The orders arriving in [0, ``duration_s``) s at ``jobs_per_hour`` on average (module
    docstring), in order of arrival; ``exclude``: nodes that are no dock (the charging nodes)."""
    faces = roadmap.nodes_of("aisle")
    docks = [n for n in roadmap.nodes_of("end") or roadmap.nodes_of("junction") if n not in exclude]
    if not faces or not docks:
        raise ValueError(f"map {roadmap.map_id!r}: no rack face or no dock on its roadmap")
    lo, hi = payload_kg
    rng = np.random.default_rng([seed, 46])
    out: list[Order] = []
    t = float(rng.exponential(3600.0 / jobs_per_hour))
    while t < duration_s:
        job = Job(
            f"job-{len(out) + 1}",
            faces[int(rng.integers(len(faces)))],
            docks[int(rng.integers(len(docks)))],
            max(MIN_PAYLOAD_KG, round(float(rng.uniform(lo, hi)), 1)),
        )
        out.append(Order(job, round(t, 3)))
        t += float(rng.exponential(3600.0 / jobs_per_hour))
    return out
