"""``amr-twin fleet --live``: every robot's topics served under its namespace, read by a client
of our own writing (tests/foxglove_client.py: ``websockets`` + the published protocol) and
rosbags' CDR."""

import collections
import sys
from pathlib import Path

import pytest

from foxglove_client import FoxgloveClient, start_cli

pytest.importorskip("websockets")
pytest.importorskip("foxglove")
pytest.importorskip("amqtt")

AMR_TWIN = str(Path(sys.executable).with_name("amr-twin"))
ROBOTS = ("amr-1", "amr-2")


def test_every_robot_live_under_its_namespace():
    from rosbags.typesys import Stores, get_typestore

    store = get_typestore(Stores.ROS2_HUMBLE)
    proc, url = start_cli(
        [
            "fleet",
            "--robots",
            "2",
            "--starts",
            "0,0,0;2,0,0",
            "--world",
            "aisles",
            "--duration-s",
            "8",
            "--live",
            "--port",
            "0",
        ],
        AMR_TWIN,
    )
    try:
        with FoxgloveClient(url) as client:
            wanted = [f"/{n}/{t}" for n in ROBOTS for t in ("odom", "scan", "battery_state")]
            client.wait_for_channels([*wanted, "/clock", "/tf", "/tf_static"])
            advertised = set(client.channels)
            client.subscribe([*wanted, "/tf_static"])
            got = client.pump(3.0)
    finally:
        _out, err = proc.communicate(timeout=120)
    assert proc.returncode == 0, err[-2000:]
    assert not {"/odom", "/scan", "/battery_state"} & advertised  # no robot outside its namespace
    counts = collections.Counter(topic for _w, topic, _t, _d in got)
    for name in ROBOTS:
        assert counts[f"/{name}/odom"] >= 20, counts  # 50 Hz for ~3 s paced at real time
        assert counts[f"/{name}/scan"] >= 5, counts
    odom = [counts[f"/{n}/odom"] for n in ROBOTS]
    assert max(odom) - min(odom) <= 0.2 * max(odom), odom
    for _w, topic, _t, data in got:
        if topic.endswith("/odom"):
            msg = store.deserialize_cdr(data, "nav_msgs/msg/Odometry")
            name = topic.split("/")[1]
            assert (msg.header.frame_id, msg.child_frame_id) == (
                f"{name}/odom",
                f"{name}/base_link",
            )
    statics = [
        store.deserialize_cdr(d, "tf2_msgs/msg/TFMessage")
        for _w, t, _t, d in got
        if t == "/tf_static"
    ]
    assert statics, "no /tf_static for the late subscriber"
    frames = {tf.child_frame_id for tf in statics[0].transforms}
    assert {f"{n}/{f}" for n in ROBOTS for f in ("odom", "laser")} <= frames
