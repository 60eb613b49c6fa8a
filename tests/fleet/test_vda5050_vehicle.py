"""The twin as a VDA 5050 2.0 vehicle through the embedded broker, driven by a master written to the
specification (vda_master.py): orders reach their last node, cancelOrder and startPause stop the
robot, bad orders are answered in the state; every message the vehicle publishes is valid against
the official 2.0.0 schemas."""

from __future__ import annotations

import math
import time

import pytest

pytest.importorskip("amqtt")
pytest.importorskip("paho.mqtt")

from vda_master import (  # noqa: E402
    Master,
    deliver,
    edge,
    instant,
    last_state,
    node,
    order,
    run_until,
    settle_and_check_schemas,
    validate,
)

START = (-6.0, 0.0, 0.0)  # the warehouse's central aisle, its west end


@pytest.fixture
def vehicle(request):
    from amr_twin.fleet.session import FleetOptions, FleetSession
    from amr_twin.model.config import load_config

    seed = getattr(request, "param", 0)
    session = FleetSession(
        load_config(), FleetOptions(world="warehouse", starts=(START,), rate=0, seed=seed)
    )
    master = Master(session.url)
    session.run(2.5)  # the EKF's rest calibration, the vehicle localised
    yield session, master
    master.close()
    session.close()


TWO_NODES = order(
    "o1",
    [node("n0", 0, -6.0, 0.0), node("n1", 2, -3.0, 0.0, theta=0.0)],
    [edge("e1", 1, "n0", "n1")],
)


@pytest.mark.parametrize("vehicle", [0, 1], indirect=True)
def test_a_two_node_order_ends_at_the_last_node_and_every_message_is_valid(vehicle):
    session, master = vehicle
    deliver(session, master, "order", TWO_NODES)
    deliver(session, master, "instantActions", instant("fs", "factsheetRequest"))
    run_until(
        session,
        lambda: last_state(session)["lastNodeId"] == "n1" and not last_state(session)["driving"],
        40,
    )
    x, y, _yaw = session.vehicles[0].true_pose()
    assert math.hypot(x + 3.0, y) < 0.3, (x, y)
    state = last_state(session)
    assert (
        state["orderId"],
        state["lastNodeSequenceId"],
        state["nodeStates"],
        state["edgeStates"],
    ) == ("o1", 2, [], [])
    assert state["errors"] == []
    settle_and_check_schemas(session, master)
    assert master.of("factsheet") and master.of("connection")[-1]["connectionState"] == "ONLINE"
    driving = [m["driving"] for m in master.of("state")]
    assert True in driving and not driving[-1]


def test_cancel_order_stops_the_robot_short_of_the_goal(vehicle):
    session, master = vehicle
    far = order(
        "o2", [node("n0", 0, -6.0, 0.0), node("n1", 2, 4.0, 0.0)], [edge("e1", 1, "n0", "n1")]
    )
    deliver(session, master, "order", far)
    run_until(session, lambda: session.vehicles[0].true_pose()[0] > -5.0, 20)
    deliver(session, master, "instantActions", instant("c1", "cancelOrder"))
    session.run(3.0)
    state = last_state(session)
    x_stop = session.vehicles[0].true_pose()[0]
    session.run(2.0)
    assert abs(session.vehicles[0].true_pose()[0] - x_stop) < 0.02  # it stands
    assert x_stop < 1.0  # short of the goal 4 m on
    status = {a["actionId"]: a["actionStatus"] for a in state["actionStates"]}
    assert status["c1"] == "FINISHED" and not state["driving"]
    assert (state["orderId"], state["nodeStates"], state["edgeStates"]) == ("o2", [], [])
    deliver(
        session, master, "instantActions", instant("c2", "cancelOrder")
    )  # nothing left to cancel
    state = last_state(session)
    assert {a["actionId"]: a["actionStatus"] for a in state["actionStates"]}["c2"] == "FAILED"
    assert [e["errorType"] for e in state["errors"]] == ["noOrderToCancel"]
    settle_and_check_schemas(session, master)


def test_start_pause_holds_the_robot_and_stop_pause_resumes_the_order(vehicle):
    session, master = vehicle
    deliver(session, master, "order", TWO_NODES)
    run_until(session, lambda: session.vehicles[0].true_pose()[0] > -5.5, 20)
    deliver(session, master, "instantActions", instant("p1", "startPause"))
    session.run(2.0)
    x_paused = session.vehicles[0].true_pose()[0]
    session.run(3.0)
    state = last_state(session)
    assert abs(session.vehicles[0].true_pose()[0] - x_paused) < 0.02 and x_paused < -3.5
    assert (
        state["paused"]
        and not state["driving"]
        and [n["nodeId"] for n in state["nodeStates"]] == ["n1"]
    )
    assert {a["actionId"]: a["actionStatus"] for a in state["actionStates"]}["p1"] == "FINISHED"
    deliver(session, master, "instantActions", instant("p2", "stopPause"))
    run_until(session, lambda: last_state(session)["lastNodeId"] == "n1", 30)
    assert (
        math.hypot(session.vehicles[0].true_pose()[0] + 3.0, session.vehicles[0].true_pose()[1])
        < 0.3
    )
    assert not last_state(session)["paused"]
    settle_and_check_schemas(session, master)


def test_bad_orders_are_answered_with_errors_in_the_state_and_a_good_one_is_still_driven(vehicle):
    session, master = vehicle
    unknown = order(
        "bad", [node("n0", 0, -6.0, 0.0), node("n1", 2, -3.0, 0.0)], [edge("e1", 1, "n0", "nX")]
    )
    deliver(session, master, "order", unknown, header_id=5)
    errors = last_state(session)["errors"]
    assert [e["errorType"] for e in errors] == ["validationError"]
    assert {"referenceKey": "endNodeId", "referenceValue": "nX"} in errors[0]["errorReferences"]
    deliver(session, master, "order", TWO_NODES, header_id=3)  # older than the last order message
    errors = last_state(session)["errors"]
    assert [e["errorType"] for e in errors] == ["validationError"] * 2
    assert {"referenceKey": "headerId", "referenceValue": "3"} in errors[1]["errorReferences"]
    assert last_state(session)["orderId"] == "" and not session.vehicles[0].adapter.route.nodes
    deliver(session, master, "order", TWO_NODES, header_id=6)
    assert last_state(session)["errors"] == [] and last_state(session)["orderId"] == "o1"
    run_until(
        session,
        lambda: last_state(session)["lastNodeId"] == "n1" and not last_state(session)["driving"],
        40,
    )
    assert (
        math.hypot(session.vehicles[0].true_pose()[0] + 3.0, session.vehicles[0].true_pose()[1])
        < 0.3
    )
    settle_and_check_schemas(session, master)


def test_the_horizon_waits_for_an_order_update_stitched_at_the_last_base_node(vehicle):
    session, master = vehicle
    first = order(
        "o3",
        [
            node("n0", 0, -6.0, 0.0),
            node("n1", 2, -4.0, 0.0),
            node("n2", 4, -2.0, 0.0, released=False),
        ],
        [edge("e1", 1, "n0", "n1"), edge("e2", 3, "n1", "n2", released=False)],
    )
    deliver(session, master, "order", first)
    run_until(
        session,
        lambda: last_state(session)["lastNodeId"] == "n1" and not last_state(session)["driving"],
        30,
    )
    session.run(2.0)
    state = last_state(session)
    assert state["newBaseRequest"] and [n["nodeId"] for n in state["nodeStates"]] == ["n2"]
    assert (
        math.hypot(session.vehicles[0].true_pose()[0] + 4.0, session.vehicles[0].true_pose()[1])
        < 0.3
    )  # waits at n1
    wrong = order(
        "o3", [node("n0", 0, -6.0, 0.0), node("n2", 2, -2.0, 0.0)], [edge("e2", 1, "n0", "n2")], 1
    )
    deliver(session, master, "order", wrong)
    assert [e["errorType"] for e in last_state(session)["errors"]] == ["orderUpdateError"]
    update = order(
        "o3",
        [node("n1", 2, -4.0, 0.0), node("n2", 4, -2.0, 0.0, theta=0.0)],
        [edge("e2", 3, "n1", "n2")],
        2,
    )
    deliver(session, master, "order", update)
    run_until(
        session,
        lambda: last_state(session)["lastNodeId"] == "n2" and not last_state(session)["driving"],
        30,
    )
    state = last_state(session)
    assert (state["orderUpdateId"], state["lastNodeSequenceId"], state["errors"]) == (2, 4, [])
    assert (
        math.hypot(session.vehicles[0].true_pose()[0] + 2.0, session.vehicles[0].true_pose()[1])
        < 0.3
    )
    settle_and_check_schemas(session, master)


def test_a_broken_connection_leaves_the_last_will(vehicle):
    session, master = vehicle
    session.vehicles[
        0
    ].transport.client.socket().close()  # no DISCONNECT: the broker sends the will
    deadline = time.monotonic() + 10
    while not any(m["connectionState"] == "CONNECTIONBROKEN" for m in master.of("connection")):
        assert time.monotonic() < deadline
        time.sleep(0.05)
    for msg in master.of("connection"):
        validate("connection", msg)


def test_an_order_through_debians_mosquitto(tmp_path):
    """The user's broker (--vda5050): Debian's mosquitto 2.0 (apt-get install mosquitto), else
    skipped."""
    import shutil
    import subprocess

    from amr_twin.fleet.broker import free_port
    from amr_twin.fleet.session import FleetOptions, FleetSession
    from amr_twin.model.config import load_config

    exe = shutil.which("mosquitto") or shutil.which("/usr/sbin/mosquitto")
    if exe is None:
        pytest.skip("mosquitto is not installed (apt-get install mosquitto)")
    port = free_port()
    broker = subprocess.Popen(
        [exe, "-p", str(port)], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL
    )
    try:
        time.sleep(0.5)
        session = FleetSession(
            load_config(),
            FleetOptions(
                world="warehouse", starts=(START,), rate=0, url=f"mqtt://127.0.0.1:{port}"
            ),
        )
        master = Master(session.url)
        try:
            session.run(2.5)
            deliver(session, master, "order", TWO_NODES)
            run_until(
                session,
                lambda: (
                    last_state(session)["lastNodeId"] == "n1" and not last_state(session)["driving"]
                ),
                40,
            )
            assert (
                math.hypot(
                    session.vehicles[0].true_pose()[0] + 3.0, session.vehicles[0].true_pose()[1]
                )
                < 0.3
            )
            settle_and_check_schemas(session, master)
        finally:
            master.close()
            session.close()
    finally:
        broker.terminate()
        broker.wait(10)
