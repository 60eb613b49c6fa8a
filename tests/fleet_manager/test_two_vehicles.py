"""The fleet manager through the embedded broker drives two robots of one warehouse world (serial
numbers amr-1 and amr-2, each with its own navigation stack, seeing the other with its LiDAR)
head-on along the central aisle: its reservations keep them apart, both jobs finish without a
physical collision, and every message it sends is valid against the VDA 5050 2.0.0 schemas."""

from __future__ import annotations

import json
import math
import sys
import time
from pathlib import Path

import jsonschema
import pytest

pytest.importorskip("amqtt")
pytest.importorskip("paho.mqtt")
sys.path.insert(0, str(Path(__file__).parents[1] / "fleet"))

from roadmaps import node_at, warehouse  # noqa: E402
from vda_master import SCHEMAS, validate  # noqa: E402

ROBOT_LENGTH_M = 0.70  # the factsheet's length


def test_two_robots_of_one_world_head_on_in_one_aisle_are_kept_apart_and_both_jobs_finish():
    from amr_twin.fleet.broker import EmbeddedBroker
    from amr_twin.fleet.session import FleetOptions, FleetSession
    from amr_twin.fleet_manager.dispatcher import ManagerOptions
    from amr_twin.fleet_manager.jobs import Job
    from amr_twin.fleet_manager.manager import FleetManager
    from amr_twin.model.config import load_config

    roadmap = warehouse()
    west, mid, east, far = (node_at(roadmap, x, 0.0) for x in (-2.7, -0.2, 2.2, 4.7))
    starts = {"amr-1": roadmap.xy(west), "amr-2": roadmap.xy(far)}
    cfg = load_config()
    broker = EmbeddedBroker().start()
    session, manager = None, None
    try:
        session = FleetSession(
            cfg,
            FleetOptions(
                world="warehouse",
                starts=((*starts["amr-1"], 0.0), (*starts["amr-2"], math.pi)),
                url=broker.url,
                rate=0,
            ),
        )
        assert session.serials == ("amr-1", "amr-2")
        manager = FleetManager(
            broker.url, roadmap, list(starts), "uagv", ManagerOptions(charging_nodes=("n0",))
        )
        for _ in range(15):  # the EKF's rest calibration: the vehicles localised and placed
            session.run(0.2)
            time.sleep(0.02)
        manager.submit([Job("job-1", mid, east, 20.0)])  # amr-1 is nearer: west to east
        session.run(0.2)
        time.sleep(0.1)
        manager.submit([Job("job-2", east, west, 10.0)])  # amr-2: east to west, head-on
        t_end = session.world.t_s + 120.0
        while manager.jobs_left() and session.world.t_s < t_end:
            session.run(0.1)
        run = session.summary()
        summary = manager.summary()
    finally:
        if manager is not None:
            manager.close()
        if session is not None:
            session.close()
        broker.stop()
    events = summary["events"]
    closest = run["least_distance_m"]
    print(summary["messages_sent"], closest, [e for e in events if e["event"] != "placed"])
    assert summary["jobs_done"] == 2 and summary["jobs_failed"] == 0, events
    assert run["collisions"] == [], run["collisions"]
    apart_m = math.dist(starts["amr-1"], starts["amr-2"])
    assert ROBOT_LENGTH_M <= closest < apart_m - 1.0, closest  # apart, yet they met in the aisle
    waits = [e for e in events if e["event"] == "wait"]
    assert any(e["vehicle"] == "amr-2" and e["waits_for"] == ["amr-1"] for e in waits), waits
    for _serial, sub, msg in manager.log:
        if sub == "order":
            validate(sub, msg)
        else:
            schema = json.loads((SCHEMAS / "instantActions.schema").read_text())
            jsonschema.Draft202012Validator(schema).validate(msg)
