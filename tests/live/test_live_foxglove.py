"""The twin live over the Foxglove WebSocket protocol, checked by a client of our own
writing (tests/foxglove_client.py: ``websockets`` + the published protocol) and rosbags' CDR.

The two acceptance runs are the issue's commands, run by the CLI in a subprocess at real
time (10 s and 15 s of wall time): rates and clock are measured on what the client receives.
"""

import math
import sys
from pathlib import Path

import numpy as np
import pytest

from foxglove_client import FoxgloveClient, start_cli

pytest.importorskip("websockets")
pytest.importorskip("foxglove")

AMR_TWIN = str(Path(sys.executable).with_name("amr-twin"))
MEASURE_S = 5.0


@pytest.fixture(scope="module")
def typestore():
    from rosbags.typesys import Stores, get_typestore

    return get_typestore(Stores.ROS2_HUMBLE)


def _mcap_channels(path):
    """topic -> (schema name, schema encoding, schema text, message encoding) and topic -> {(log
    time, payload)}."""
    from mcap.reader import make_reader

    channels, messages = {}, {}
    with open(path, "rb") as f:
        for schema, channel, message in make_reader(f).iter_messages():
            channels[channel.topic] = (
                schema.name,
                schema.encoding,
                schema.data.decode(),
                channel.message_encoding,
            )
            messages.setdefault(channel.topic, set()).add((message.log_time, message.data))
    return channels, messages


def test_scan_and_odom_live_at_their_rates_as_in_the_mcap(tmp_path, typestore):
    """Acceptance 1: /scan and /odom advertised with their ROS 2 schemas in CDR as in the .mcap
    (the same run writes one), received at their rates within 10 %, the simulated time going
    with the wall clock within 5 %. Every channel of the .mcap is served, with the same bytes."""
    from amr_twin.model.config import load_config
    from amr_twin.recording.mcap_log import LATCHED

    mcap = tmp_path / "run.mcap"
    proc, url = start_cli(
        [
            "run",
            "linear",
            "--speed-m-s",
            "0.3",
            "--duration-s",
            "10",
            "--world",
            "empty",
            "--sensors",
            "--live",
            "--port",
            "0",
            "--mcap",
            str(mcap),
        ],
        AMR_TWIN,
    )
    try:
        with FoxgloveClient(url) as client:
            client.wait_for_channels(["/scan", "/odom", "/clock"])
            topics = sorted(set(client.channels) - {"/twin/scene", "/cmd_vel"})
            client.subscribe(topics)
            got = client.pump(MEASURE_S)
            advertised = dict(client.channels)
    finally:
        out, err = proc.communicate(timeout=120)
    assert proc.returncode == 0, err[-2000:]

    channels, recorded = _mcap_channels(mcap)
    assert set(channels) <= set(advertised)  # every channel of the .mcap, with its schema, live
    for topic in channels:
        ch = advertised[topic]
        assert (ch["schemaName"], ch["schemaEncoding"], ch["schema"], ch["encoding"]) == channels[
            topic
        ], topic
    assert advertised["/scan"]["schemaName"] == "sensor_msgs/msg/LaserScan"
    assert advertised["/odom"]["schemaName"] == "nav_msgs/msg/Odometry"
    received = {name for _w, name, _t, _d in got}
    assert (
        set(channels)
        - {"/twin/collisions", "/twin/faults", "/wheel_Command", "/wheel_Command_Service/request"}
        <= received
    )  # (the command was sent at t = 0, before the client came)
    for (
        _w,
        topic,
        t,
        data,
    ) in got:  # the same CDR bytes at the same log times (latched: the same bytes)
        if topic in LATCHED:
            assert data in {d for _t, d in recorded[topic]}, topic
        else:
            assert (t, data) in recorded[topic], (topic, t)

    cfg = load_config()
    nominal_hz = {"/scan": cfg.lidar.scan_rate_hz, "/odom": 50.0, "/clock": 100.0}
    for topic, hz in nominal_hz.items():
        wall = np.array([w for w, name, _t, _d in got if name == topic])
        rate_hz = (len(wall) - 1) / (wall[-1] - wall[0])
        assert rate_hz == pytest.approx(hz, rel=0.10), topic
    clock = [(w, t) for w, name, t, _d in got if name == "/clock"]
    sim_s, wall_s = (clock[-1][1] - clock[0][1]) * 1e-9, clock[-1][0] - clock[0][0]
    assert wall_s > 0.8 * MEASURE_S and sim_s / wall_s == pytest.approx(1.0, rel=0.05)

    scan = typestore.deserialize_cdr(
        [d for _w, name, _t, d in got if name == "/scan"][-1], "sensor_msgs/msg/LaserScan"
    )
    assert scan.header.frame_id == "laser" and len(scan.ranges) > 300
    assert scan.time_increment < 0 < scan.angle_increment and scan.range_max == pytest.approx(12.0)
    assert "pose x" in out


def test_teleop_twist_drives_the_twin_and_the_watchdog_stops_it(typestore):
    """Acceptance 2: a client advertising /cmd_vel publishes 0.3 m/s for 3 s at 10 Hz on an idle
    twin; /odom moves 0.6-1.1 m forward; the diff-drive node stops the wheels 0.5 s after the
    last Twist and the robot (ground truth) is at rest soon after."""
    import time

    proc, url = start_cli(
        ["run", "stop", "--duration-s", "15", "--world", "empty", "--live", "--port", "0"], AMR_TWIN
    )
    topics = ["/odom", "/cmd_vel", "/wheel_Command", "/twin/ground_truth"]
    Twist, Vector3 = (
        typestore.types["geometry_msgs/msg/Twist"],
        typestore.types["geometry_msgs/msg/Vector3"],
    )
    forward = typestore.serialize_cdr(
        Twist(linear=Vector3(0.3, 0.0, 0.0), angular=Vector3(0.0, 0.0, 0.0)),
        "geometry_msgs/msg/Twist",
    )
    try:
        with FoxgloveClient(url) as client:
            client.wait_for_channels(topics)
            client.subscribe(topics)
            channel = client.advertise("/cmd_vel", "geometry_msgs/msg/Twist")
            got = client.pump(0.3)
            start = time.monotonic()
            for i in range(30):  # 10 Hz for 3 s, on the wall clock
                client.publish(channel, forward)
                client.pump(start + 0.1 * (i + 1) - time.monotonic(), got)
            client.pump(60.0, got, until=lambda: client.closed)  # to the end of the run
    finally:
        out, err = proc.communicate(timeout=120)
    assert proc.returncode == 0, err[-2000:]

    def decoded(topic, typ):
        return [
            (t * 1e-9, typestore.deserialize_cdr(d, typ)) for _w, name, t, d in got if name == topic
        ]

    cmd_vel = decoded("/cmd_vel", "geometry_msgs/msg/Twist")
    assert len(cmd_vel) == 30 and all(
        m.linear.x == 0.3 for _t, m in cmd_vel
    )  # every Twist reached the bus
    gaps = np.diff([t for t, _m in cmd_vel])
    assert gaps.max() < 0.5  # paced: never a watchdog gap between two of them
    commands = decoded("/wheel_Command", "std_msgs/msg/Float64MultiArray")
    rpm = 0.3 * 60 / (math.pi * 0.25)
    assert [list(m.data) for _t, m in commands] == [
        pytest.approx([1, rpm, 1, rpm], rel=1e-6),
        [0, 0, 0, 0],
    ]
    assert commands[0][0] == pytest.approx(cmd_vel[0][0], abs=1e-6)
    assert commands[1][0] - cmd_vel[-1][0] == pytest.approx(
        0.5, abs=1e-6
    )  # the watchdog, to the microsecond

    odom = decoded("/odom", "nav_msgs/msg/Odometry")
    x = odom[-1][1].pose.pose.position.x
    assert 0.6 <= x <= 1.1 and abs(odom[-1][1].pose.pose.position.y) < 0.05
    truth = decoded("/twin/ground_truth", "nav_msgs/msg/Odometry")
    t_stop = commands[1][0]
    moving = [
        t for t, m in truth if math.hypot(m.twist.twist.linear.x, m.twist.twist.linear.y) > 0.01
    ]
    assert moving and t_stop < moving[-1] < t_stop + 1.0  # braked to rest within 1 s of the stop
    travelled = truth[-1][1].pose.pose.position.x - truth[0][1].pose.pose.position.x
    assert 0.8 < travelled < 1.1
