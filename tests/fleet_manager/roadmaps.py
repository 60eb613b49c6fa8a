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


def warehouse_lanes():
    """The roadmap of the warehouse world with lanes, as the fleet manager drives it (a copy)."""
    from amr_twin.fleet_manager.lanes import lane_roadmap
    from amr_twin.fleet_manager.roadmap import MARGIN_M

    return lane_roadmap(warehouse(), _warehouse_radius(), MARGIN_M)


@lru_cache(maxsize=1)
def _warehouse_radius() -> float:
    from amr_twin.model.config import load_config
    from amr_twin.navigation.footprint import robot_footprint

    return robot_footprint(load_config()).circumscribed_radius_m
