"""The warehouse's roadmap with lanes: two one-way lanes in the central aisle and the east column,
lay-bys at the central aisle's rack faces, the north and south aisles one way round the rack rows;
robots following each other in a lane; and physics-free fleets of 1 to 8 vehicles carrying jobs
faster the more they are, without a deadlock."""

from __future__ import annotations

import math

import networkx as nx
import pytest

from fake_vehicles import drive
from roadmaps import warehouse, warehouse_lanes

pytest.importorskip("mujoco")


def _heading(roadmap, u, v) -> tuple[float, float]:
    (x0, y0), (x1, y1) = roadmap.xy(u), roadmap.xy(v)
    return x1 - x0, y1 - y0


def test_the_central_aisle_has_two_opposite_lanes_and_the_outer_aisles_run_one_way():
    roadmap = warehouse_lanes()
    graph = roadmap.graph
    assert graph.is_directed() and nx.is_strongly_connected(graph)

    def edges_along(y, kind=None):
        return [
            (u, v)
            for u, v in graph.edges
            if abs(roadmap.xy(u)[1] - y) < 0.2
            and abs(roadmap.xy(v)[1] - y) < 0.2
            and (kind is None or graph.nodes[u]["kind"] == kind)
        ]

    # right-hand traffic: eastbound south of the centre line, westbound north of it, ~0.94 m off
    east, west = edges_along(-0.965, "lane"), edges_along(0.915, "lane")
    assert len(east) >= 3 and all(_heading(roadmap, u, v)[0] > 0 for u, v in east)
    assert len(west) >= 3 and all(_heading(roadmap, u, v)[0] < 0 for u, v in west)
    assert all(graph.edges[e]["oneway"] for e in east + west)
    # north aisle eastbound, south aisle westbound: clockwise round each rack row
    north, south = edges_along(5.525), edges_along(-5.575)
    assert len(north) >= 4 and all(_heading(roadmap, u, v)[0] > 0 for u, v in north)
    assert len(south) >= 4 and all(_heading(roadmap, u, v)[0] < 0 for u, v in south)
    # the docks (dead ends) stay two-way
    for dock in roadmap.nodes_of("end"):
        (mouth,) = graph.successors(dock)
        assert graph.has_edge(mouth, dock) and not graph.edges[dock, mouth]["oneway"]


def test_picks_in_the_central_aisle_are_at_lay_bys_off_the_through_lanes():
    roadmap = warehouse_lanes()
    graph = roadmap.graph
    bays = [n for n, bay in graph.nodes(data="bay") if bay]
    assert len(bays) == 8 and set(bays) <= set(roadmap.nodes_of("aisle"))
    for bay in bays:
        (lane,), (after,) = graph.predecessors(bay), graph.successors(bay)
        assert graph.has_edge(lane, after)  # the lane runs past it
        assert 2.3 < abs(roadmap.xy(bay)[1]) < 2.45  # at the rack face (racks at y = +-3)
        assert math.dist(roadmap.xy(bay), roadmap.xy(lane)) > 2 * 0.44 + 0.3
    assert not {n for n in graph if graph.nodes[n]["kind"] == "lane"} & set(
        roadmap.nodes_of("aisle")
    )


def test_every_lane_node_stands_where_the_robot_turns_in_place_with_its_margin():
    from amr_twin.fleet_manager.roadmap import MARGIN_M
    from amr_twin.fleet_manager.skeleton import clearance_m
    from amr_twin.model.config import load_config
    from amr_twin.navigation.footprint import robot_footprint
    from amr_twin.navigation.stack import true_map

    cfg = load_config()
    static = true_map(cfg, "warehouse")
    clear = clearance_m(static.occupied, static.resolution_m)
    radius = robot_footprint(cfg).circumscribed_radius_m
    roadmap = warehouse_lanes()
    for n in roadmap.graph:
        x, y = roadmap.xy(n)
        col = int((x - static.origin_xy_m[0]) / static.resolution_m)
        row = int((y - static.origin_xy_m[1]) / static.resolution_m)
        assert clear[row, col] >= radius + MARGIN_M - 0.05, (n, x, y, clear[row, col])


def test_a_roadmap_without_a_wide_corridor_is_left_undirected():
    from amr_twin.fleet_manager.lanes import lane_roadmap

    roadmap = warehouse()
    for _u, _v, d in roadmap.graph.edges(data=True):
        d["width_m"] = min(d["width_m"], 2.8)
    assert lane_roadmap(roadmap, 0.44, 0.15) is roadmap


def test_a_robot_follows_another_along_a_lane_node_by_node():
    from amr_twin.fleet_manager.traffic import LOOKAHEAD_NODES, Traffic

    roadmap = warehouse_lanes()
    traffic = Traffic(roadmap.graph)
    lane = ["n11a", "n14a", "n18a", "n21a", "n26", "n27a"]
    traffic.place("amr-1", "n11a")
    traffic.place("amr-2", "n8")
    traffic.assign("amr-1", lane)
    traffic.assign("amr-2", ["n8", *lane])
    first = traffic.extend("amr-1")
    assert first.held == LOOKAHEAD_NODES and not first.waits_for
    assert traffic.extend("amr-2").waits_for == {"amr-1"}
    traffic.advance("amr-1", 1)  # amr-1 passed n14a: amr-2 takes n11a right behind it
    second = traffic.extend("amr-2")
    assert second.held == 1 and traffic.held_by("amr-2") == ["n8", "n11a"]
    assert traffic.deadlock() is None
    # the opposite lane stays free meanwhile: a robot westbound is not held up
    traffic.place("amr-3", "n21b")
    traffic.assign("amr-3", ["n21b", "n18b", "n14b", "n11b"])
    assert traffic.extend("amr-3").held == 3


def test_a_robot_picking_in_a_lay_by_does_not_hold_up_the_lane():
    from amr_twin.fleet_manager.traffic import Traffic

    roadmap = warehouse_lanes()
    traffic = Traffic(roadmap.graph)
    traffic.place("amr-1", "n14ap")  # standing at the rack face, picking
    traffic.place("amr-2", "n11a")
    traffic.assign("amr-2", ["n11a", "n14a", "n18a", "n21a"])
    assert traffic.extend("amr-2").held == 3


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_more_vehicles_carry_the_jobs_in_fewer_steps_without_a_deadlock(seed):
    steps = {}
    for vehicles in (1, 2, 4, 8):
        done, steps[vehicles], events = drive(
            warehouse_lanes(), vehicles, 40, seed, steps=1200, pool_docks=True
        )
        assert done == 40, (vehicles, [e for e in events if e["event"] == "failed"][-3:])
        assert not [e for e in events if e["event"] == "deadlock"], vehicles
    assert steps[2] < 0.6 * steps[1] and steps[4] < 0.7 * steps[2], steps
    assert steps[8] <= steps[4], steps
