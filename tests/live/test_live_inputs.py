"""What a live client sends the twin. Good messages drive it through the bus; anything
else is logged, counted and dropped, and the twin runs on.

The decoders are checked on payloads made by rosbags' own CDR serializer; the server in-process,
with the twin advanced by the test between the client's messages (rate 0: no sleeping).
"""

import logging
import math
import struct
import time

import numpy as np
import pytest

from amr_twin.live import inputs as live_inputs
from amr_twin.live.inputs import InputError

from foxglove_client import FoxgloveClient

pytest.importorskip("websockets")
pytest.importorskip("foxglove")


@pytest.fixture(scope="module")
def typestore():
    from rosbags.typesys import Stores, get_typestore

    return get_typestore(Stores.ROS2_HUMBLE)


def _twist(typestore, vx, wz, big_endian=False):
    T, V = typestore.types["geometry_msgs/msg/Twist"], typestore.types["geometry_msgs/msg/Vector3"]
    msg = T(linear=V(vx, 0.0, 0.0), angular=V(0.0, 0.0, wz))
    return typestore.serialize_cdr(msg, "geometry_msgs/msg/Twist", little_endian=not big_endian)


def _array(typestore, values):
    from rosbags.typesys.stores.ros2_humble import std_msgs__msg__MultiArrayLayout as Layout

    A = typestore.types["std_msgs/msg/Float64MultiArray"]
    return typestore.serialize_cdr(
        A(layout=Layout(dim=[], data_offset=0), data=np.array(values, float)),
        "std_msgs/msg/Float64MultiArray",
    )


def test_twist_decoded_from_either_byte_order_and_json(typestore):
    for payload, encoding in (
        (_twist(typestore, 0.3, -0.2), "cdr"),
        (_twist(typestore, 0.3, -0.2, True), "cdr"),
        (b'{"linear": {"x": 0.3}, "angular": {"z": -0.2}}', "json"),
    ):
        twist = live_inputs.decode_twist(payload, encoding)
        assert (twist.linear.x, twist.linear.y, twist.angular.z) == (0.3, 0.0, -0.2)


@pytest.mark.parametrize(
    "payload,encoding,why",
    [
        (b"", "cdr", "does not decode"),
        (b"\x00\x01\x00\x00" + bytes(20), "cdr", "does not decode"),
        (b"\x00\x01\x00\x00" + struct.pack("<6d", math.nan, 0, 0, 0, 0, 0), "cdr", "linear.x=nan"),
        (b"\x00\x01\x00\x00" + struct.pack("<6d", 0, 0, 0, 0, 0, math.inf), "cdr", "angular.z=inf"),
        (b'{"linear": {"x": "fast"}}', "json", "linear.x='fast'"),
        (b"[1, 2]", "json", "not a JSON object"),
        (b"\xff\xfe", "json", "does not decode"),
        (b"{}", "protobuf", "encoding 'protobuf'"),
        (b"\x00\x01\x00\x00" + bytes(1 << 20), "cdr", "more than a geometry_msgs/Twist can take"),
    ],
)
def test_bad_twists_refused_in_one_line(payload, encoding, why):
    with pytest.raises(InputError, match=why.replace("(", r"\(").replace("[", r"\[")) as info:
        live_inputs.decode_twist(payload, encoding)
    assert "\n" not in str(info.value)


def test_wheel_requests_checked(typestore):
    req = live_inputs.decode_request_topic(_array(typestore, [1, 30.0, -1, 12.5]), "cdr")
    assert (req.motionL, req.speedL, req.motionR, req.speedR) == (1, 30.0, -1, 12.5)
    srv = live_inputs.decode_service_request(
        b"\x00\x01\x00\x00" + struct.pack("<ifif", -1, 20.0, 0, 0.0), "cdr"
    )
    assert (srv.motionL, srv.speedL, srv.motionR, srv.speedR) == (-1, 20.0, 0, 0.0)
    srv = live_inputs.decode_service_request(
        b'{"motionL": 1, "speedL": 5, "motionR": 1, "speedR": 5}', "json"
    )
    assert (srv.motionL, srv.speedR) == (1, 5.0)
    for values, why in (
        ([1, 30.0, 1], "3 values"),
        ([2, 30.0, 1, 30.0], "motionL=2"),
        ([1, -5.0, 1, 5.0], "speedL=-5"),
        ([1, 5.0, 1, 5000.0], "speedR=5000"),
        ([1, math.nan, 1, 5.0], "speedL=nan"),
    ):
        with pytest.raises(InputError, match=why):
            live_inputs.decode_request_topic(_array(typestore, values), "cdr")
    with pytest.raises(InputError, match="expected 20"):
        live_inputs.decode_service_request(b"\x00\x01\x00\x00" + bytes(8), "cdr")
    for topic, typ, why in (
        ("/foo", "geometry_msgs/msg/Twist", "the twin takes"),
        ("/cmd_vel", "std_msgs/msg/String", "expected geometry_msgs/msg/Twist"),
        ("/cmd_vel", "geometry_msgs/msg/Twist", "encoding 'ros1'"),
    ):
        with pytest.raises(InputError, match=why):
            live_inputs.input_for(topic, typ, "ros1" if "ros1" in why else "cdr")


@pytest.fixture()
def served():
    """An idle twin (stop at t = 0) served on a free port, unpaced; the test advances it."""
    from amr_twin.model.config import load_config
    from amr_twin.live.session import LiveOptions, LiveSession
    from amr_twin.assembly.twin import Twin, TwinOptions

    twin = Twin(load_config(), TwinOptions(world="empty"))
    twin.client.stop()
    session = LiveSession(twin, LiveOptions(port=0, rate=0.0), say=lambda _line: None)
    commands = []
    twin.bus.add_tap(
        lambda topic, msg, t_us: (
            commands.append((t_us, list(msg.data))) if topic == "wheel_Command" else None
        )
    )
    yield twin, session, commands
    session.close()


def _settle(client, sink, n, timeout_s=10.0):
    """Pump until the server has judged ``n`` client messages in all."""
    client.pump(timeout_s, until=lambda: sink.clients.accepted + sink.dropped >= n)
    assert sink.clients.accepted + sink.dropped >= n


def test_malformed_and_unknown_messages_dropped_the_twin_runs_on(served, typestore, caplog):
    twin, session, commands = served
    sink = session.sink
    with (
        FoxgloveClient(sink.url) as client,
        caplog.at_level(logging.WARNING, logger="amr_twin.live.foxglove_clients"),
    ):
        client.wait_for_channels(["/odom"])
        good = client.advertise("/cmd_vel", "geometry_msgs/msg/Twist")
        as_json = client.advertise("/cmd_vel", "geometry_msgs/msg/Twist", encoding="json")
        wrong_type = client.advertise("/cmd_vel", "std_msgs/msg/String")
        unknown = client.advertise("/foo", "geometry_msgs/msg/Twist")
        request = client.advertise(
            "/wheel_Command_Service/request", "std_msgs/msg/Float64MultiArray"
        )
        client.pump(0.2)
        bad = [
            (good, b"\x00\x01\x00\x00" + bytes(7)),  # truncated CDR
            (good, b"\x00\x01\x00\x00" + struct.pack("<6d", math.nan, 0, 0, 0, 0, 0)),
            (good, np.random.default_rng(0).bytes(1 << 20)),  # 1 MiB of noise
            (as_json, b"{not json"),
            (as_json, b'{"linear": {"x": [1]}}'),
            (wrong_type, _twist(typestore, 0.3, 0.0)),
            (unknown, _twist(typestore, 0.3, 0.0)),
            (request, _array(typestore, [1, 30.0, 1])),
            (request, _array(typestore, [3, 30.0, 1, 30.0])),
        ]
        for channel, payload in bad:
            client.publish(channel, payload)
        client.publish(
            999, _twist(typestore, 0.3, 0.0)
        )  # never advertised: the SDK itself refuses it
        _settle(client, sink, len(bad))
        client.pump(0.2, until=lambda: client.statuses)
        assert "999" in client.statuses[-1]["message"]
        twin.advance(0.5)
        assert sink.dropped == len(bad) and sink.clients.accepted == 0 and commands == []
        assert len(
            [r for r in caplog.records if r.getMessage().startswith("live: dropped")]
        ) == len(bad)
        assert all("\n" not in r.getMessage() for r in caplog.records)

        client.publish(
            as_json, b'{"linear": {"x": 0.2}, "angular": {"z": 0.5}}'
        )  # turning left (REP-103)
        client.publish(request, _array(typestore, [1, 30.0, -1, 30.0]))
        _settle(client, sink, len(bad) + 2)
        twin.advance(0.1)
        half_m = twin.client.half_separation_m
        left, right = ((0.2 + s * 0.5 * half_m) * 60 / (math.pi * 0.25) for s in (-1, 1))
        assert [c for _t, c in commands] == [
            pytest.approx([1, left, 1, right], rel=1e-6),
            [1, 30.0, -1, 30.0],
        ]

        # a service call waits for the twin's next tick: the twin runs in a thread meanwhile
        with _running(twin):
            reply = client.call_service(
                "/wheel_Command_Service", b"\x00\x01\x00\x00" + struct.pack("<ifif", 1, 10, 1, 10)
            )
            refused = client.call_service("/wheel_Command_Service", b"\x00\x01\x00\x00" + bytes(4))
        assert reply == ("cdr", live_inputs.EMPTY_RESPONSE_CDR)
        assert [1, 10.0, 1, 10.0] in [
            c for _t, c in commands[2:]
        ]  # (with the watchdog's stop around it)
        assert refused is None and "expected 20" in client.failures[-1]["message"]
    assert session.sink.clients.accepted == 3 and session.sink.dropped == len(bad) + 1


class _running:
    """Advance ``twin`` in a thread (unpaced, 0.1 s at a time) while the block runs."""

    def __init__(self, twin):
        import threading

        self.twin, self.stop = twin, threading.Event()
        self.thread = threading.Thread(target=self._run)

    def _run(self):
        while not self.stop.is_set():
            self.twin.advance(0.1)
            time.sleep(0.005)

    def __enter__(self):
        self.thread.start()

    def __exit__(self, *exc):
        self.stop.set()
        self.thread.join()


def test_latched_topics_and_scene_reach_a_late_subscriber(served):
    """/tf_static, /robot_description and /twin/scene come again to a client that subscribes late;
    the SceneUpdate (decoded with protobuf from the advertised descriptor) draws the world in
    odom and each robot link in its own tf frame."""
    pytest.importorskip("google.protobuf")
    import base64

    from google.protobuf import descriptor_pb2, descriptor_pool, message_factory

    twin, session, _commands = served
    twin.advance(1.0)
    with FoxgloveClient(session.sink.url) as client:
        client.wait_for_channels(["/twin/scene", "/tf_static", "/robot_description"])
        client.subscribe(["/twin/scene", "/tf_static", "/robot_description"])
        client.pump(0.3)
        twin.advance(0.2)
        got = client.pump(1.0)
        scene_channel = client.channels["/twin/scene"]
    topics = [name for _w, name, _t, _d in got]
    assert "/tf_static" in topics and "/robot_description" in topics
    assert (
        scene_channel["schemaEncoding"] == "protobuf"
        and scene_channel["schemaName"] == "foxglove.SceneUpdate"
    )
    files = descriptor_pb2.FileDescriptorSet.FromString(base64.b64decode(scene_channel["schema"]))
    pool = descriptor_pool.DescriptorPool()
    for f in files.file:
        pool.Add(f)
    SceneUpdate = message_factory.GetMessageClass(
        pool.FindMessageTypeByName("foxglove.SceneUpdate")
    )
    entities = {}
    for _w, name, _t, data in got:
        if name == "/twin/scene":
            for e in SceneUpdate.FromString(data).entities:
                entities[e.id] = e
    links = {e.frame_id for k, e in entities.items() if k.startswith("robot/")}
    assert {"base_link", "wheel_left_link", "wheel_right_link", "laser"} <= links
    assert all(entities[f"robot/{link}"].frame_locked for link in links)
    world = entities["world"]
    assert world.frame_id == "odom" and len(world.cubes) >= 1  # the floor
    floor = world.cubes[0]
    base_z = twin.physics.data.xpos[1][2]
    assert floor.pose.position.z == pytest.approx(
        -base_z, abs=0.01
    )  # the floor, seen from odom's origin
    ghost = entities["ground_truth"]
    assert (
        ghost.frame_id == "odom"
        and len(ghost.cubes) + len(ghost.cylinders) + len(ghost.spheres) > 10
    )
