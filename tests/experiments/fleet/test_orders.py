"""Seeded order streams: rack face to dock, payloads in range, arrivals at the rate."""

import pytest

from amr_twin.experiments.fleet.orders import order_stream
from amr_twin.fleet_manager.roadmap import world_roadmap
from amr_twin.model.config import load_config


@pytest.fixture(scope="module")
def roadmap():
    return world_roadmap(load_config(), "warehouse")


def test_same_seed_same_stream_and_another_seed_another(roadmap):
    a = order_stream(roadmap, (0.0, 30.0), 120.0, 3600.0, 3)
    assert a == order_stream(roadmap, (0.0, 30.0), 120.0, 3600.0, 3)
    assert a != order_stream(roadmap, (0.0, 30.0), 120.0, 3600.0, 4)


def test_orders_pick_at_rack_faces_drop_at_docks_with_payloads_in_range(roadmap):
    orders = order_stream(roadmap, (0.0, 30.0), 600.0, 36000.0, 0, exclude={"n31"})
    assert 5700 < len(orders) < 6300  # 600 an hour for 10 h
    times = [o.arrival_s for o in orders]
    assert times == sorted(times) and 0 < times[0] and times[-1] < 36000.0
    assert {o.job.pick for o in orders} <= set(roadmap.nodes_of("aisle"))
    docks = {o.job.drop for o in orders}
    assert docks <= set(roadmap.nodes_of("end")) and "n31" not in docks
    kg = [o.job.payload_kg for o in orders]
    assert min(kg) >= 0.1 and max(kg) <= 30.0 and 13.0 < sum(kg) / len(kg) < 17.0


def test_a_fixed_payload_keeps_the_stream_of_places_and_times(roadmap):
    light = order_stream(roadmap, (0.0, 0.0), 300.0, 600.0, 0)
    heavy = order_stream(roadmap, (50.0, 50.0), 300.0, 600.0, 0)
    assert [(o.job.pick, o.job.drop, o.arrival_s) for o in light] == [
        (o.job.pick, o.job.drop, o.arrival_s) for o in heavy
    ]
    assert {o.job.payload_kg for o in light} == {0.1} and {o.job.payload_kg for o in heavy} == {
        50.0
    }
