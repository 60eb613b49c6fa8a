"""The warehouse world's roadmap: its aisles where the world has them, as wide as they are, nodes
on free floor where the robot turns in place, and routes along them."""

from __future__ import annotations

import math

import networkx as nx
import pytest

from roadmaps import node_at, warehouse

pytest.importorskip("mujoco")


def test_the_warehouse_roadmap_runs_along_its_three_aisles_and_round_the_racks():
    roadmap = warehouse()
    graph = roadmap.graph
    assert nx.is_connected(graph)
    # the central aisle (racks at y = -3 and 3), the north and south aisles (racks to the walls)
    for y, width in ((0.0, 5.9), (5.5, 2.8), (-5.55, 2.2)):
        on = [n for n in graph if abs(roadmap.xy(n)[1] - y) < 0.15]
        assert len(on) >= 4, (y, on)
        widths = [graph.edges[a, b]["width_m"] for a in on for b in graph[a] if b in on]
        assert widths and all(abs(w - width) < 0.25 for w in widths), (y, widths)
    # a loop round each rack row: the central aisle can be bypassed
    central = [n for n in graph if abs(roadmap.xy(n)[1]) < 0.15 and abs(roadmap.xy(n)[0]) < 3]
    assert nx.is_connected(graph.subgraph(set(graph) - set(central)))
    assert all(d["length_m"] <= 2.7 + 1e-9 for _, _, d in graph.edges(data=True))
    assert sorted(roadmap.xy(n) for n in roadmap.nodes_of("end")) == [
        (-9.375, -0.725),
        (9.175, -6.175),
        (9.175, 6.175),
    ]


def test_every_node_stands_where_the_robot_turns_in_place():
    from amr_twin.fleet_manager.skeleton import clearance_m
    from amr_twin.model.config import load_config
    from amr_twin.navigation.footprint import robot_footprint
    from amr_twin.navigation.stack import true_map

    cfg = load_config()
    static = true_map(cfg, "warehouse")
    clear = clearance_m(static.occupied, static.resolution_m)
    radius = robot_footprint(cfg).circumscribed_radius_m
    roadmap = warehouse()
    for n in roadmap.graph:
        x, y = roadmap.xy(n)
        col = int((x - static.origin_xy_m[0]) / static.resolution_m)
        row = int((y - static.origin_xy_m[1]) / static.resolution_m)
        assert clear[row, col] >= radius, (n, x, y, clear[row, col])
        pos = roadmap.position(n)
        assert (pos["mapId"], pos["allowedDeviationXY"]) == ("warehouse", 0.3)


def test_a_route_is_the_shortest_way_and_avoids_what_it_is_told_to():
    roadmap = warehouse()
    west, east = node_at(roadmap, -5.4, 0.5), node_at(roadmap, 7.2, -0.2)
    direct = roadmap.route(west, east)
    assert all(abs(roadmap.xy(n)[1]) < 0.6 for n in direct)
    assert roadmap.length_m(direct) == pytest.approx(
        math.dist(roadmap.xy(west), roadmap.xy(east)), rel=0.03
    )
    around = roadmap.route(west, east, avoid=set(direct[1:-1]))
    assert around is not None and roadmap.length_m(around) > roadmap.length_m(direct) + 10


def test_a_vehicle_off_the_roadmap_is_joined_to_its_nearest_node():
    roadmap = warehouse()
    near = node_at(roadmap, -5.4, 0.5)
    assert roadmap.attach("amr-1-home", -5.3, 0.4) == near  # within the allowed deviation
    home = roadmap.attach("amr-1-home", -6.0, 0.0)
    assert home == "amr-1-home" and list(roadmap.graph[home]) == [near]
    assert roadmap.graph.edges[home, near]["length_m"] == pytest.approx(
        math.dist((-6, 0), roadmap.xy(near))
    )
