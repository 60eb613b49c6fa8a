"""The twin under an independent master control: Siemens' vda-5050-lib MasterController
(vda5050_master/master.mjs, Node) through Debian's mosquitto drives ``amr-twin fleet`` along the
warehouse's central aisle; the order is processed without error, the robot stops within the last
node's allowed deviation, and every message the twin sends passes the library's 2.0 validators and
the official 2.0.0 schemas. Skipped, saying why, without node, the npm packages or mosquitto."""

from __future__ import annotations

import json
import math
import shutil
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import pytest

pytest.importorskip("paho.mqtt")
pytest.importorskip("jsonschema")

from vda_master import Master, validate  # noqa: E402

FOLDER = Path(__file__).parent / "vda5050_master"
MOSQUITTO = shutil.which("mosquitto") or shutil.which("/usr/sbin/mosquitto")
VEHICLE_TOPICS = ("state", "visualization", "connection", "factsheet")
FLEET = [sys.executable, "-c", "from amr_twin.cli.main import main; main()", "fleet"]


def _missing() -> str | None:
    """Why the master cannot run here, or None."""
    if shutil.which("node") is None:
        return "node is not installed"
    if not (FOLDER / "node_modules" / "vda-5050-lib").is_dir():
        return f"vda-5050-lib is not installed: run npm ci in {FOLDER}"
    if MOSQUITTO is None:
        return "mosquitto is not installed"
    return None


needs_master = pytest.mark.skipif(_missing() is not None, reason=str(_missing()))


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@pytest.fixture
def broker():
    port = _free_port()
    proc = subprocess.Popen(
        [MOSQUITTO, "-p", str(port)], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL
    )
    deadline = time.monotonic() + 10
    while True:
        try:
            socket.create_connection(("127.0.0.1", port), 0.2).close()
            break
        except OSError:
            assert proc.poll() is None and time.monotonic() < deadline, "mosquitto did not start"
            time.sleep(0.05)
    yield f"mqtt://127.0.0.1:{port}"
    proc.terminate()
    proc.wait(10)


def run_fleet_under_master(
    url: str, starts: str = "-6,0,0", vehicles: tuple = ("amr-1",), timeout_s: int = 45
) -> tuple[dict, dict, list]:
    """The twin (its robots at ``starts``, one at the west end of the central aisle by default)
    and master.mjs for ``vehicles`` on ``url``: the master's report, the twin's ``--json``
    summary, and every vehicle message a listener saw."""
    listener = Master(url, vehicles)
    robots = str(len(vehicles))
    twin = subprocess.Popen(
        FLEET
        + ["--robots", robots, "--world", "warehouse", "--starts", starts, "--vda5050", url]
        + ["--rate", "10", "--duration-s", "300", "--json"],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        master = subprocess.run(
            ["node", str(FOLDER / "master.mjs"), "--broker", url, "--timeout-s", str(timeout_s)]
            + ["--vehicles", ",".join(vehicles)],
            capture_output=True,
            text=True,
            timeout=timeout_s + 15,
        )
        time.sleep(0.3)  # the listener gets what is in flight
    finally:
        twin.send_signal(signal.SIGINT)  # the twin says OFFLINE and prints its summary
        out, err = twin.communicate(timeout=60)
        listener.close()
    assert master.stdout.strip(), master.stderr[-2000:]
    assert twin.returncode == 0, err[-2000:]
    return json.loads(master.stdout), json.loads(out), listener.received


@needs_master
def test_vda_5050_lib_master_controller_drives_the_twin_along_the_central_aisle(broker):
    report, twin, received = run_fleet_under_master(broker)
    assert report["ok"], (report["failures"], report["rejected"])
    vehicle = report["vehicles"]["amr-1"]
    assert vehicle["processed"]["withError"] is None and not vehicle["processed"]["byCancelation"]
    traversed = [e["nodeId"] for e in vehicle["events"] if e["event"] == "nodeTraversed"]
    assert traversed == ["amr-1-start", "amr-1-middle", "amr-1-end"]
    assert report["rejected"] == [] and vehicle["stateErrors"] == []
    assert all(report["accepted"].get(t, 0) > 0 for t in VEHICLE_TOPICS), report["accepted"]
    last = vehicle["lastNode"]
    pose = twin["true_pose"]
    assert (last["x"], last["y"]) == (4, 0)  # the aisle's east end, 10 m from the start
    assert (
        math.hypot(pose["x_m"] - last["x"], pose["y_m"] - last["y"]) <= last["allowedDeviationXy"]
    )
    assert twin["last_state"]["errors"] == [] and twin["last_state"]["lastNodeId"] == "amr-1-end"
    sent = [(t, m) for t, m in received if t in VEHICLE_TOPICS]
    assert {t for t, _m in sent} == set(VEHICLE_TOPICS)
    for subtopic, msg in sent:  # the official 2.0.0 schemas too
        validate(subtopic, msg)


@needs_master
def test_vda_5050_lib_master_controller_swaps_two_robots_head_on_along_the_central_aisle(broker):
    report, twin, received = run_fleet_under_master(
        broker, "-6,0,0;4,0,180", ("amr-1", "amr-2"), timeout_s=75
    )
    assert report["ok"], (report["failures"], report["rejected"])
    assert report["rejected"] == []
    assert twin["collisions"] == [], twin["collisions"]
    ends = {"amr-1": (4, 0), "amr-2": (-6, 0)}  # each to the other's start
    for served in twin["vehicles"]:
        serial = served["serialNumber"]
        vehicle = report["vehicles"][serial]
        assert vehicle["processed"]["withError"] is None, vehicle["processed"]
        assert vehicle["stateErrors"] == []
        last, pose = vehicle["lastNode"], served["true_pose"]
        assert (last["x"], last["y"]) == ends[serial]
        deviation = math.hypot(pose["x_m"] - last["x"], pose["y_m"] - last["y"])
        assert deviation <= last["allowedDeviationXy"], (serial, pose)
    assert {m["serialNumber"] for t, m in received if t == "state"} == {"amr-1", "amr-2"}
    for subtopic, msg in received:
        if subtopic in VEHICLE_TOPICS:
            validate(subtopic, msg)


@pytest.mark.parametrize("key", ["allowedDeviationXy", "allowedDeviationXY"])
def test_the_schemas_and_the_texts_spelling_of_the_allowed_deviation_are_read(key):
    from amr_twin.fleet.order_message import parse_order
    from vda_master import edge, node, order

    nodes = [node("n0", 0, -6.0, 0.0), node("n1", 2, -3.0, 0.0)]
    nodes[1]["nodePosition"][key] = 0.7
    msg = {"headerId": 1, **order("o1", nodes, [edge("e1", 1, "n0", "n1")])}
    assert parse_order(msg, "warehouse").nodes[1].deviation_xy_m == 0.7
