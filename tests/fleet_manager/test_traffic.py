"""Traffic control on the warehouse's roadmap: two robots sent head-on along the central aisle (the
second waits at the aisle's end until the first is through), a drive of both to the end that never
puts them on one edge or node, and a deadlock found as a cycle."""

from __future__ import annotations

import pytest

from roadmaps import node_at, warehouse

pytest.importorskip("mujoco")


@pytest.fixture
def aisle():
    """The roadmap, the central aisle's west and east junctions and its inner nodes west to east,
    the traffic control."""
    from amr_twin.fleet_manager.traffic import Traffic

    roadmap = warehouse()
    west, east = node_at(roadmap, -5.1, 0.2), node_at(roadmap, 7.1, -0.1)
    inner = roadmap.route(west, east)[1:-1]
    return roadmap, west, east, inner, Traffic(roadmap.graph)


def test_the_second_robot_sent_head_on_into_an_aisle_waits_at_its_end(aisle):
    roadmap, west, east, inner, traffic = aisle
    traffic.place("amr-1", inner[0])
    traffic.place("amr-2", east)
    traffic.assign("amr-1", roadmap.route(inner[0], inner[-1]))
    traffic.assign("amr-2", roadmap.route(east, west))
    second = traffic.extend("amr-2")  # asks first, but amr-1 is in the aisle already
    first = traffic.extend("amr-1")
    assert first.held == len(inner) - 1 and not first.waits_for  # through to its goal
    assert second.held == 0 and second.waits_for == {"amr-1"}  # not one node into the aisle
    assert traffic.held_by("amr-2") == [east]
    for i in range(1, len(inner)):  # amr-1 drives on; amr-2 still waits: amr-1 ends in the aisle
        traffic.advance("amr-1", i)
        assert traffic.extend("amr-2").held == 0


def test_two_robots_crossing_the_aisle_never_share_an_edge_or_a_node_and_both_arrive(aisle):
    roadmap, west, east, inner, traffic = aisle
    south_east, north_east = (node_at(roadmap, 7.4, y) for y in (-2.0, 1.7))
    traffic.place("amr-1", inner[0])
    traffic.place("amr-2", north_east)
    traffic.assign("amr-1", roadmap.route(inner[0], south_east))  # east through the aisle
    traffic.assign("amr-2", roadmap.route(north_east, west))  # west through the aisle
    for _step in range(40):
        spots = {}
        for serial in ("amr-1", "amr-2"):
            traffic.extend(serial)
            plan = traffic.plans[serial]
            if plan.held > plan.passed:
                a, b = plan.route[plan.passed], plan.route[plan.passed + 1]
                spots[serial] = frozenset((a, b))  # on the edge a-b ...
                traffic.advance(serial, plan.passed + 1)  # ... then at b
        assert len(set(spots.values())) == len(spots), spots
        held = [traffic.held_by(s) for s in ("amr-1", "amr-2")]
        assert not set(held[0]) & set(held[1])
    assert traffic.plans["amr-1"].done and traffic.plans["amr-2"].done


def test_two_robots_each_at_the_other_ones_end_of_the_aisle_are_a_deadlock(aisle):
    roadmap, west, east, inner, traffic = aisle
    traffic.place("amr-1", west)
    traffic.place("amr-2", east)
    beyond_east, beyond_west = node_at(roadmap, 7.4, -2.0), node_at(roadmap, -6.4, 1.0)
    traffic.assign("amr-1", roadmap.route(west, beyond_east))  # through amr-2's junction
    traffic.assign("amr-2", roadmap.route(east, beyond_west))  # through amr-1's
    assert traffic.extend("amr-1").waits_for == {"amr-2"}
    assert traffic.extend("amr-2").waits_for == {"amr-1"}
    assert traffic.deadlock() in (["amr-1", "amr-2"], ["amr-2", "amr-1"])
    traffic.place("amr-2", node_at(roadmap, 7.4, 1.7))  # amr-2 taken off elsewhere: amr-1 goes
    assert traffic.deadlock() is None and traffic.extend("amr-1").held == len(inner) + 2


def test_a_node_held_by_another_vehicle_cannot_be_taken():
    from amr_twin.fleet_manager.traffic import Traffic

    roadmap = warehouse()
    traffic = Traffic(roadmap.graph)
    node = node_at(roadmap, -0.2, 0.0)
    assert traffic.place("amr-1", node) and not traffic.place("amr-2", node)
    with pytest.raises(ValueError, match="where the vehicle stands"):
        traffic.assign("amr-1", [node_at(roadmap, 2.2, 0.0)])
