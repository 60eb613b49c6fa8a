"""The warehouse world's roadmap, built once for the fleet manager's tests (a fresh copy each call:
attaching a vehicle adds a node)."""

from __future__ import annotations

import copy
from functools import lru_cache


@lru_cache(maxsize=1)
def _warehouse():
    from amr_twin.fleet_manager.roadmap import build_roadmap
    from amr_twin.model.config import load_config
    from amr_twin.navigation.footprint import robot_footprint
    from amr_twin.navigation.stack import true_map

    cfg = load_config()
    return build_roadmap(
        true_map(cfg, "warehouse"), "warehouse", robot_footprint(cfg).circumscribed_radius_m
    )


def warehouse():
    """The roadmap of the warehouse world (a copy)."""
    return copy.deepcopy(_warehouse())


def node_at(roadmap, x: float, y: float) -> str:
    """The id of the node within 0.5 m of (x, y)."""
    node, dist = roadmap.nearest(x, y)
    assert dist < 0.5, (x, y, node, dist)
    return node
