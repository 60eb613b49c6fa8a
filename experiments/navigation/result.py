"""The navigation experiment's results: its settings, each map's (or hall group's) summary, every
episode's row and the time it took, as ``metrics.json`` holds them (:meth:`as_json`).

The summaries and rows keep the keys of ``metrics.json``
(:func:`amr_twin.experiments.navigation.metrics.summary`,
:func:`amr_twin.experiments.navigation.metrics.measure`).
"""

from __future__ import annotations

from dataclasses import dataclass, field, fields

OPTIMAL = (
    "shortest path of the robot's centre in the visibility graph of the true world's obstacles "
    "(unmapped ones included) grown by the footprint's inscribed radius: a lower bound"
)
"""What the rows' optimal length is (``optimal`` of ``metrics.json``)."""


def _as_json(result) -> dict:
    """``result``'s fields in their order, the static maps left out."""
    return {f.name: getattr(result, f.name) for f in fields(result) if f.name != "static_maps"}


@dataclass
class NavigationResult:
    """The episodes on a world's true and SLAM maps (:func:`.experiment.run`).

    Args:
        summary: each metric by ``map/scenario`` (``true/all``, ``slam/person``, ...).
        rows: one row per episode and map.
        slam_map: the SLAM map's file and how it was built (None: the true map only).
        wall_s, cpu_s: the run's wall time and CPU time of all processes, s.
        static_maps: each map's static layer (for the figures; not in ``metrics.json``).
    """

    world: str
    episodes: int
    seed: int
    people: str
    maps: list[str]
    localisation: str
    controller: str
    firmware: str
    slam_map: dict | None
    optimal: str
    summary: dict[str, dict]
    rows: list[dict]
    jobs: int
    wall_s: float
    cpu_s: float
    static_maps: dict = field(default_factory=dict, repr=False)

    def as_json(self) -> dict:
        """The result as ``metrics.json`` holds it."""
        return _as_json(self)


@dataclass
class HallsResult:
    """The episodes on generated halls, the tuning halls and the held-out ones apart
    (:func:`.experiment.run_halls`).

    Args:
        groups: the halls of ``tuning`` and of ``held_out``.
        summary: per group its halls, its episodes' metrics, its door trips and the people's cost.
        by_world: each hall's door trips against its other episodes.
        rows, rows_without_people: the episodes, and those with a walking person run without them.
        wall_s, cpu_s: the run's wall time and CPU time of all processes, s.
        static_maps: each hall's true map (for the figures; not in ``metrics.json``).
    """

    worlds: list[str]
    groups: dict[str, list[str]]
    episodes: int
    seed: int
    people: str
    maps: list[str]
    localisation: str
    controller: str
    firmware: str
    optimal: str
    summary: dict[str, dict]
    by_world: dict[str, dict]
    rows: list[dict]
    rows_without_people: list[dict]
    jobs: int
    wall_s: float
    cpu_s: float
    static_maps: dict = field(default_factory=dict, repr=False)

    def as_json(self) -> dict:
        """The result as ``metrics.json`` holds it."""
        return _as_json(self)
