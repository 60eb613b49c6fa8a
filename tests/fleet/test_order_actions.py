"""Node actions as parsed from an order, and the load and charging actions' refusals, without a
broker or a twin (a stand-in vehicle)."""

from __future__ import annotations

import re

import pytest

from amr_twin.fleet.actions import NODE_ACTIONS, Action
from amr_twin.fleet.handling import Handling, Load
from amr_twin.fleet.order import Rejection
from amr_twin.fleet.order_message import parse_order
from amr_twin.model.worlds import ChargingStation


class StandIn:
    """A vehicle that stands at ``pose`` and records what the handling asks of it."""

    def __init__(self, pose=(0.0, 0.0, 0.0)):
        self._pose, self.payload_kg, self.charging = pose, [], []

    def pose(self):
        return self._pose

    def set_payload_kg(self, mass_kg):
        self.payload_kg.append(mass_kg)

    def set_charging(self, on):
        self.charging.append(on)


def _order(actions):
    node = {
        "nodeId": "n0",
        "sequenceId": 0,
        "released": True,
        "nodePosition": {"x": 0.0, "y": 0.0, "mapId": "m"},
        "actions": actions,
    }
    return {"headerId": 1, "orderId": "o", "orderUpdateId": 0, "nodes": [node], "edges": []}


def test_a_nodes_actions_are_parsed_with_their_blocking_type_and_parameters():
    pick = {
        "actionId": "p",
        "actionType": "pick",
        "blockingType": "HARD",
        "actionParameters": [{"key": "weight", "value": 20}, {"key": "loadId", "value": "b"}],
    }
    order = parse_order(_order([pick]), "m", NODE_ACTIONS)
    assert order.nodes[0].actions == (
        Action("p", "pick", "HARD", (("weight", 20), ("loadId", "b"))),
    )
    with pytest.raises(Rejection, match="blockingType must be one of NONE, SOFT, HARD") as bad:
        parse_order(_order([{**pick, "blockingType": "FIRM"}]), "m", NODE_ACTIONS)
    assert bad.value.error_type == "validationError"
    with pytest.raises(Rejection, match="action pick is not one this vehicle performs"):
        parse_order(_order([pick]), "m", frozenset())


def _pick(weight=20.0, **more):
    params = {} if weight is None else {"weight": weight}
    return Action("p", "pick", "HARD", tuple({**params, **more}.items()))


def test_a_pick_takes_the_handling_time_then_the_vehicle_carries_it_and_a_drop_takes_it_off():
    vehicle = StandIn()
    h = Handling(vehicle, 50.0, 10.0)
    assert h.start(_pick(20.0, loadId="b", loadType="KLT"), 5.0, True) == ("RUNNING", None)
    assert h.step(14.9) is None and vehicle.payload_kg == [] and h.busy
    action, result = h.step(15.0)
    assert (action.action_id, result, vehicle.payload_kg) == ("p", "load on the deck", [20.0])
    assert h.loads() == [{"weight": 20.0, "loadId": "b", "loadType": "KLT"}]
    with pytest.raises(Rejection, match="loadId 'x' is not the load carried"):
        h.start(Action("d", "drop", "HARD", (("loadId", "x"),)), 20.0, True)
    assert h.start(Action("d", "drop"), 20.0, True) == ("RUNNING", None)
    assert h.step(30.0)[1] == "deck empty" and vehicle.payload_kg == [20.0, 0.0] and h.loads() == []


@pytest.mark.parametrize(
    "action, standing, load, says",
    [
        (_pick(None), True, None, "parameter weight (kg, a number > 0) is required"),
        (_pick("20"), True, None, "parameter weight (kg, a number > 0) is required"),
        (_pick(50.5), True, None, "must be > 0 and at most the 50 kg the deck carries"),
        (_pick(-1.0), True, None, "must be > 0 and at most the 50 kg"),
        (_pick(5.0), True, Load(5.0), "the deck already carries a load"),
        (_pick(5.0), False, None, "the vehicle is moving: it must stand"),
        (Action("d", "drop"), True, None, "no load on the deck"),
        (Action("c", "startCharging"), True, None, "not at a charging station"),
    ],
)
def test_what_cannot_be_done_is_refused_with_an_action_error(action, standing, load, says):
    vehicle = StandIn()
    h = Handling(vehicle, 50.0, 10.0, (ChargingStation("c1", 5.0, 0.0, 0.0),), load=load)
    with pytest.raises(Rejection, match=re.escape(says)) as refused:
        h.start(action, 0.0, standing)
    assert refused.value.error_type == "actionError" and not h.busy
    assert vehicle.payload_kg == [] and vehicle.charging == []


def test_charging_starts_only_within_the_tolerances_of_a_station():
    station = ChargingStation("c1", 5.0, 0.0, 1.0)
    for pose, ok in (((5.2, 0.1, 1.2), True), ((5.3, 0.0, 1.0), False), ((5.0, 0.0, 1.3), False)):
        vehicle = StandIn(pose)
        h = Handling(vehicle, 50.0, 10.0, (station,), 0.25, 0.25)
        assert (h.station() is station) == ok
    h = Handling(StandIn((5.0, 0.0, 1.0)), 50.0, 10.0, (station,))
    assert h.start(Action("c", "startCharging"), 0.0, True) == ("FINISHED", "charging at c1")
    assert h.charging and h.vehicle.charging == [True]
    assert h.start(Action("s", "stopCharging"), 1.0, False) == ("FINISHED", "charging stopped")
    assert not h.charging and h.start(Action("s2", "stopCharging"), 2.0, True)[1] == "not charging"
