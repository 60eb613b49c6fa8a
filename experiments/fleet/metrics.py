"""The fleet experiment's measures, from per-robot records of any fleet size: time on orders,
lead-time percentiles, near misses between robots, energy over an interval, payload bins and
where throughput saturates.

Pure functions of lists and arrays (no twin here), so that they are tested on made-up fleets.
"""

from __future__ import annotations

import math
from itertools import combinations

import numpy as np

SATURATION_GAIN = 0.10
"""Throughput saturates at the fleet size after which the next one raises the median orders per
hour by less than this share."""


def busy_intervals(events: list[dict], serial: str, end_s: float) -> list[tuple[float, float]]:
    """The spans (s) in which vehicle ``serial`` carried a job: from the manager's ``assigned``
    event of a job task to its ``done`` or ``failed`` event (or ``end_s``)."""
    spans, start = [], None
    for e in events:
        if e.get("vehicle") != serial or e.get("task") != "job":
            continue
        if e["event"] == "assigned" and start is None:
            start = e["t_s"]
        elif e["event"] in ("done", "failed") and start is not None:
            spans.append((start, min(e["t_s"], end_s)))
            start = None
    if start is not None and start < end_s:
        spans.append((start, end_s))
    return spans


def utilisation(spans: list[tuple[float, float]], duration_s: float) -> float:
    """The share of ``duration_s`` covered by ``spans`` (0-1)."""
    return sum(b - a for a, b in spans) / duration_s


def percentiles(values: list[float], qs=(50, 95)) -> list[float | None]:
    """The ``qs`` percentiles of ``values`` (numpy's linear interpolation); None each if empty."""
    if not values:
        return [None for _ in qs]
    return [float(np.percentile(values, q)) for q in qs]


def energy_between(times_s: np.ndarray, cumulative: np.ndarray, a_s: float, b_s: float) -> float:
    """The growth of a cumulative series (energy J, charge A s) from ``a_s`` to ``b_s``,
    interpolated linearly between its samples."""
    return float(np.interp(b_s, times_s, cumulative) - np.interp(a_s, times_s, cumulative))


class NearMisses:
    """Episodes in which two robots' true centres come closer than ``threshold_m``: per pair, each
    run of samples below it is one near miss, with its first time and least distance."""

    def __init__(self, threshold_m: float):
        self.threshold_m = threshold_m
        self.episodes: list[dict] = []
        self.least_m: float | None = None
        self._open: dict[tuple[str, str], dict] = {}

    def update(self, t_s: float, positions: dict[str, tuple[float, float]]) -> None:
        """The robots' true (x_m, y_m) at ``t_s``."""
        for a, b in combinations(sorted(positions), 2):
            d = math.dist(positions[a], positions[b])
            self.least_m = d if self.least_m is None else min(self.least_m, d)
            ep = self._open.get((a, b))
            if d >= self.threshold_m:
                self._open.pop((a, b), None)
            elif ep is None:
                ep = {"robots": [a, b], "t_s": t_s, "least_m": d, "least_t_s": t_s}
                self._open[(a, b)] = ep
                self.episodes.append(ep)
            elif d < ep["least_m"]:
                ep["least_m"], ep["least_t_s"] = d, t_s


def saturation(sizes: list[int], throughputs: list[float]) -> int | None:
    """The fleet size after which orders per hour rise by less than :data:`SATURATION_GAIN`:
    the first of the ascending ``sizes`` whose next size's throughput is below
    ``(1 + SATURATION_GAIN)`` times its own; None if every step gains more (or one size only)."""
    pairs = sorted(zip(sizes, throughputs))
    for (n, q), (_n2, q2) in zip(pairs, pairs[1:]):
        if q2 < (1 + SATURATION_GAIN) * q:
            return n
    return None


def payload_bins(jobs: list[dict], edges_kg: list[float]) -> list[dict]:
    """The done jobs (``payload_kg``, ``energy_wh``, ``driving_wh``, ``distance_m``) by payload
    bin [edges[i], edges[i+1]): count, median energy per order (Wh), and the median driving
    energy per km driven (Wh/km: the energy drawn while moving, over the distance)."""
    out = []
    for lo, hi in zip(edges_kg, edges_kg[1:]):
        last = hi == edges_kg[-1]
        inside = [j for j in jobs if lo <= j["payload_kg"] < hi or (last and j["payload_kg"] == hi)]
        per_km = [1000 * j["driving_wh"] / j["distance_m"] for j in inside if j["distance_m"] > 1]
        out.append(
            {
                "payload_kg": [lo, hi],
                "orders": len(inside),
                "energy_wh_median": percentiles([j["energy_wh"] for j in inside], (50,))[0],
                "driving_wh_per_km_median": percentiles(per_km, (50,))[0],
            }
        )
    return out


def payload_slope(jobs: list[dict]) -> dict | None:
    """A least-squares line through the done jobs' driving energy per km against payload:
    ``wh_per_km_at_0kg`` and ``wh_per_km_per_10kg``; None with fewer than 3 jobs driven over 1 m
    or payloads spanning less than 1 kg."""
    pts = [
        (j["payload_kg"], 1000 * j["driving_wh"] / j["distance_m"])
        for j in jobs
        if j["distance_m"] > 1
    ]
    if len(pts) < 3 or max(p[0] for p in pts) - min(p[0] for p in pts) < 1.0:
        return None
    slope, at0 = np.polyfit([p[0] for p in pts], [p[1] for p in pts], 1)
    return {
        "orders": len(pts),
        "wh_per_km_at_0kg": round(float(at0), 3),
        "wh_per_km_per_10kg": round(10 * float(slope), 3),
    }


def bin_edges(lo_kg: float, hi_kg: float, bins: int = 3) -> list[float]:
    """``bins`` equal payload bins over [lo_kg, hi_kg] (one when the range is a single value)."""
    if hi_kg <= lo_kg:
        return [lo_kg, hi_kg]
    return [round(lo_kg + (hi_kg - lo_kg) * i / bins, 3) for i in range(bins + 1)]
