"""The ``--mcap`` recording read back with the ``rosbags`` library.

``rosbags`` is a reader independent of the ``mcap`` package that wrote the file: its
rosbag2 ``Reader`` opens a bare ``.mcap`` (rosbag2 MCAP storage, profile ``ros2``), and
its own CDR deserializer decodes every message against the ROS 2 Humble message
definitions it ships, not against the definitions embedded in the file.
"""

import collections
import math

import numpy as np
import pytest

from amr_twin.model.actors import Actor
from amr_twin.model.config import load_config
from amr_twin.assembly.twin import Twin, TwinOptions
from amr_twin.recording.rerun_capture import attach
from amr_twin.recording.rerun_log import record_run
from amr_twin.assembly.command import Command
from amr_twin.recording.run import run_mission

from uwb_run import UWB_S, record_uwb_run

DURATION_S = 4.0
STEPS = [
    (0.0, Command("linear", speed_m_s=0.5)),
    (2.0, Command("angular", speed_deg_s=-60.0, icc_m=-1.0)),
]
TOPIC_TYPES = {
    "/clock": "rosgraph_msgs/msg/Clock",
    "/robot_description": "std_msgs/msg/String",
    "/joint_states": "sensor_msgs/msg/JointState",
    "/wheel_Command_Service/request": "std_msgs/msg/Float64MultiArray",
    "/odom": "nav_msgs/msg/Odometry",
    "/tf": "tf2_msgs/msg/TFMessage",
    "/tf_static": "tf2_msgs/msg/TFMessage",
    "/scan": "sensor_msgs/msg/LaserScan",
    "/imu/data_raw": "sensor_msgs/msg/Imu",
    "/imu/mag": "sensor_msgs/msg/MagneticField",
    "/wheel0_Vel": "std_msgs/msg/Float64",
    "/wheel1_Vel": "std_msgs/msg/Float64",
    "/wheel_Command": "std_msgs/msg/Float64MultiArray",
    "/twin/true_rpm": "std_msgs/msg/Float64MultiArray",
    "/twin/pwm_counts": "std_msgs/msg/Float64MultiArray",
    "/twin/ground_truth": "nav_msgs/msg/Odometry",
    "/twin/motor_current": "std_msgs/msg/Float64MultiArray",
    "/battery_state": "sensor_msgs/msg/BatteryState",
    "/actors/poses": "geometry_msgs/msg/PoseArray",
}
ACTORS = (
    Actor("person", ((2.0, -2.0), (2.0, 2.0)), 1.2, loop=True),
    Actor("pallet_jack", ((5.0, 1.0),), 1.0),
)


@pytest.fixture(scope="module")
def recorded(tmp_path_factory):
    """One 4 s run with IMU, LiDAR and two actors, its capture, and the ``.mcap`` file it wrote."""
    cfg = load_config()
    options = TwinOptions(sensors=("imu", "lidar"), actors=ACTORS)
    twin = Twin(cfg, options)
    capture = attach(twin)
    result = run_mission(cfg, STEPS, DURATION_S, options, twin=twin)
    path = tmp_path_factory.mktemp("rosbags") / "run.mcap"
    record_run(twin, mcap_path=path, result=result)
    return cfg, capture, result, path


@pytest.fixture(scope="module")
def bag(recorded):
    """Connections, bag-level figures and every raw message, as rosbags' rosbag2 Reader gives
    them."""
    from rosbags.rosbag2 import Reader

    with Reader(recorded[3]) as reader:
        info = {
            "message_count": reader.message_count,
            "start_ns": reader.start_time,
            "end_ns": reader.end_time,
        }
        connections = list(reader.connections)
        raw = [(con.topic, con.msgtype, t_ns, data) for con, t_ns, data in reader.messages()]
    return info, connections, raw


@pytest.fixture(scope="module")
def decoded(bag):
    """topic -> [(log time ns, message)], decoded by rosbags' CDR deserializer with ROS 2 Humble
    types."""
    from rosbags.typesys import Stores, get_typestore

    humble = get_typestore(Stores.ROS2_HUMBLE)
    out = collections.defaultdict(list)
    for topic, msgtype, t_ns, data in bag[2]:
        out[topic].append((t_ns, humble.deserialize_cdr(data, msgtype)))
    return out


def _yaw_rad(q) -> float:
    return math.atan2(2.0 * (q.w * q.z + q.x * q.y), 1.0 - 2.0 * (q.y * q.y + q.z * q.z))


def test_bare_mcap_opens_as_rosbag2_storage(bag):
    from rosbags.interfaces import MessageDefinitionFormat

    info, connections, raw = bag
    assert {c.topic: c.msgtype for c in connections} == TOPIC_TYPES
    for con in connections:
        assert con.ext.serialization_format == "cdr", con.topic
        assert con.msgdef.format == MessageDefinitionFormat.MSG, (
            con.topic
        )  # schema encoding ros2msg
    counts = collections.Counter(topic for topic, *_ in raw)
    assert {c.topic: c.msgcount for c in connections} == dict(counts)  # summary statistics agree
    assert info["message_count"] == len(raw)
    assert info["start_ns"] == 0 and info["end_ns"] <= DURATION_S * 1e9 + 1
    times = [t_ns for _topic, _type, t_ns, _data in raw]
    assert times == sorted(times)


def test_embedded_definitions_are_the_ros2_humble_ones(bag):
    """The ros2msg schemas describe exactly the standard types (same fields, same RIHS01 hash)."""
    from rosbags.typesys import Stores, get_types_from_msg, get_typestore

    humble = get_typestore(Stores.ROS2_HUMBLE)
    embedded = get_typestore(Stores.EMPTY)
    for con in bag[1]:
        types = get_types_from_msg(con.msgdef.data, con.msgtype)
        assert con.msgtype in types
        for name, fields in types.items():
            assert fields == humble.fielddefs[name], (con.topic, name)
        embedded.register(types)
    for con in bag[1]:
        assert embedded.hash_rihs01(con.msgtype) == humble.hash_rihs01(con.msgtype), con.topic


def test_every_payload_is_byte_exact_cdr(bag):
    """rosbags decodes each message and encodes it back to the very same bytes (alignment,
    padding)."""
    from rosbags.typesys import Stores, get_typestore

    humble = get_typestore(Stores.ROS2_HUMBLE)
    bad = collections.Counter()
    for topic, msgtype, _t_ns, data in bag[2]:
        if bytes(humble.serialize_cdr(humble.deserialize_cdr(data, msgtype), msgtype)) != data:
            bad[topic] += 1
    assert not bad


def test_anyreader_with_the_embedded_definitions(recorded, bag):
    from rosbags.highlevel import AnyReader

    counts = collections.Counter()
    with AnyReader([recorded[3]]) as reader:
        for con, _t_ns, data in reader.messages(connections=reader.connections):
            msg = reader.deserialize(data, con.msgtype)
            assert msg.__msgtype__ == TOPIC_TYPES[con.topic]
            counts[con.topic] += 1
    assert counts == collections.Counter(topic for topic, *_ in bag[2])


def test_counts_for_the_duration_and_rates(recorded, decoded):
    cfg, capture, result, _path = recorded
    n = {topic: len(msgs) for topic, msgs in decoded.items()}
    assert n["/odom"] == len(capture.messages["odom"]) == len(capture.messages["tf"])
    assert abs(n["/odom"] - 50 * DURATION_S) <= 2
    assert (
        n["/tf"] == n["/odom"] + n["/joint_states"]
    )  # odometry + the joints' links (robot_state_publisher)
    assert abs(n["/joint_states"] - 50 * DURATION_S) <= 2
    assert n["/scan"] == len(capture.messages["scan"])
    assert abs(n["/scan"] - cfg.lidar.scan_rate_hz * DURATION_S) <= 2
    assert n["/imu/data_raw"] == n["/imu/mag"] == len(capture.messages["imu/data_raw"])
    assert abs(n["/imu/data_raw"] - cfg.imu.rate_hz * DURATION_S) <= 2
    for wheel in (0, 1):
        assert n[f"/wheel{wheel}_Vel"] == len(result.series.published[wheel]) >= 2
    assert n["/wheel_Command"] == n["/wheel_Command_Service/request"] == len(STEPS)
    assert n["/twin/true_rpm"] == n["/twin/pwm_counts"] == len(result.series.t_s)
    assert (
        n["/twin/ground_truth"] == n["/clock"] == len(capture.state.t_us) == len(result.series.t_s)
    )
    assert n["/tf_static"] == n["/robot_description"] == 1


def test_values_against_the_simulation(recorded, decoded):
    _cfg, capture, result, _path = recorded
    series = result.series
    # odometry: last pose as the recorder saw it; stamp = log time = bus time
    t_ns, odom = decoded["/odom"][-1]
    assert (odom.header.frame_id, odom.child_frame_id) == ("odom", "base_link")
    assert odom.header.stamp.sec * 10**9 + odom.header.stamp.nanosec == t_ns
    p = odom.pose.pose.position
    assert (p.x, p.y) == pytest.approx(tuple(series.odom[-1, 1:3]), abs=1e-12)
    assert _yaw_rad(odom.pose.pose.orientation) == pytest.approx(series.odom[-1, 3], abs=1e-9)
    # /tf carries the same transform
    tf = [
        m.transforms[0] for _t, m in decoded["/tf"] if m.transforms[0].child_frame_id == "base_link"
    ][-1]
    assert (tf.header.frame_id, tf.child_frame_id) == ("odom", "base_link")
    assert tf.transform.translation.x == p.x
    # ground truth and true wheel speeds at every recorded row
    truth = np.array(
        [
            (m.pose.pose.position.x, m.pose.pose.position.y, _yaw_rad(m.pose.pose.orientation))
            for _t, m in decoded["/twin/ground_truth"]
        ]
    )
    assert np.allclose(truth[:, :2], series.pose[:, :2], atol=1e-12)
    assert np.allclose(np.angle(np.exp(1j * (truth[:, 2] - series.pose[:, 2]))), 0.0, atol=1e-9)
    true_rpm = np.array([m.data for _t, m in decoded["/twin/true_rpm"]])
    assert np.array_equal(true_rpm, series.true_rpm)
    assert [t for t, _m in decoded["/twin/true_rpm"]] == np.round(series.t_s * 1e9).astype(
        np.int64
    ).tolist()
    pwm = np.array([m.data for _t, m in decoded["/twin/pwm_counts"]])
    assert np.array_equal(pwm, series.pwm_counts)
    # electrics: motor currents at every row, the pack at 10 Hz (ROS: current negative discharging)
    current = np.array([m.data for _t, m in decoded["/twin/motor_current"]])
    assert np.array_equal(current, series.current_a) and current.max() > 1.0
    battery = [m for _t, m in decoded["/battery_state"]]
    assert len(battery) == len(series.t_s[::10])
    assert [b.voltage for b in battery] == pytest.approx(series.battery_v[::10].tolist(), rel=1e-6)
    assert [b.current for b in battery] == pytest.approx(
        (-series.battery_a[::10]).tolist(), rel=1e-6
    )
    assert all(b.current < 0 for b in battery)  # the pack discharges
    assert battery[-1].percentage < battery[0].percentage == pytest.approx(_cfg.battery.soc_initial)
    # firmware topics: published RPM and the wheel commands
    for wheel in (0, 1):
        rpm = [m.data for _t, m in decoded[f"/wheel{wheel}_Vel"]]
        assert rpm == pytest.approx(series.published[wheel][:, 1].tolist())
    commands = np.array([m.data for _t, m in decoded["/wheel_Command"]])
    assert np.array_equal(commands, np.array([c for _t, c in series.commands]))
    requests = [m for _t, m in decoded["/wheel_Command_Service/request"]]
    assert np.array_equal(
        [m.data for m in requests], commands
    )  # the calls, as the service got them
    assert requests[0].layout.dim[0].label == "motionL,speedL,motionR,speedR"
    assert np.allclose(
        commands[-1], [1, 99.2, 1, 60.8], rtol=1e-6
    )  # the chapter 5 clockwise turn (float32)
    # sensors: the last scan and IMU sample as published on the bus
    scan, src = decoded["/scan"][-1][1], capture.messages["scan"][-1][1]
    assert scan.header.frame_id == "laser"
    assert np.array_equal(scan.ranges, np.asarray(src.ranges, np.float32), equal_nan=True)
    assert scan.angle_increment == pytest.approx(src.angle_increment, rel=1e-6)
    imu, imu_src = decoded["/imu/data_raw"][-1][1], capture.messages["imu/data_raw"][-1][1]
    assert imu.angular_velocity.z == imu_src.angular_velocity.z < 0  # turning clockwise
    assert imu.linear_acceleration.z == imu_src.linear_acceleration.z
    # static frames (REP-105): the URDF's fixed joints, no parent for odom
    static = {(t.header.frame_id, t.child_frame_id) for t in decoded["/tf_static"][0][1].transforms}
    assert static == {("base_link", "laser"), ("base_link", "imu_link"), ("base_link", "uwb_tag")}


def test_actor_poses_at_10_hz_in_the_map_frame_with_the_simulated_values(recorded, decoded):
    """/actors/poses: one PoseArray every 100 ms from t = 0, frame map, the poses the twin published
    (the walker down its segment at 1.2 m/s, the jack standing)."""
    cfg, capture, _result, _path = recorded
    msgs = decoded["/actors/poses"]
    src = capture.messages["actors/poses"]
    assert [t for t, _m in msgs] == [
        int(round(0.1 * k * 1e9)) for k in range(int(DURATION_S * 10) + 1)
    ]
    assert len(src) == len(msgs)
    for (t_ns, msg), (_t_us, want) in zip(msgs, src):
        assert (
            msg.header.frame_id == "map"
            and msg.header.stamp.sec * 10**9 + msg.header.stamp.nanosec == t_ns
        )
        assert [
            (p.position.x, p.position.y, p.orientation.z, p.orientation.w) for p in msg.poses
        ] == [(p.position.x, p.position.y, p.orientation.z, p.orientation.w) for p in want.poses]
    at_2s = msgs[20][1].poses
    assert (at_2s[0].position.x, at_2s[0].position.y) == pytest.approx((2.0, -2.0 + 1.2 * 2.0))
    assert (
        _yaw_rad(at_2s[0].orientation) == pytest.approx(math.pi / 2) and at_2s[1].position.x == 5.0
    )


def test_channels_offer_qos_profiles_tf_static_transient_local(recorded):
    """The MCAP ros2 profile requires offered_qos_profiles; /tf_static must be transient-local for
    tf2."""
    from rosbags.rosbag2 import Reader

    with Reader(recorded[3]) as reader:
        qos = {c.topic: c.ext.offered_qos_profiles for c in reader.connections}
    assert set(qos) and all(len(profiles) == 1 for profiles in qos.values())
    durability = {topic: str(profiles[0].durability) for topic, profiles in qos.items()}
    latched = {"/tf_static", "/robot_description"}
    assert all("TRANSIENT_LOCAL" in durability[t].upper() for t in latched)
    assert all("VOLATILE" in d.upper() for t, d in durability.items() if t not in latched)


@pytest.fixture(scope="module")
def uwb_bag(tmp_path_factory):
    """A 2 s run with the UWB tag only; its capture and its /uwb/range messages as rosbags reads
    them."""
    from rosbags.rosbag2 import Reader

    cfg, capture, paths = record_uwb_run(tmp_path_factory.mktemp("rosbags_uwb"), rrd=False)
    with Reader(paths["mcap"]) as reader:
        connections = {c.topic: c for c in reader.connections}
        raw = [(con.topic, con.msgtype, t_ns, data) for con, t_ns, data in reader.messages()]
    return cfg, capture, connections, raw


def test_uwb_range_topic_and_definition(uwb_bag):
    from rosbags.typesys import Stores, get_types_from_msg, get_typestore

    _cfg, _capture, connections, _raw = uwb_bag
    humble = get_typestore(Stores.ROS2_HUMBLE)
    con = connections["/uwb/range"]
    assert con.msgtype == "sensor_msgs/msg/Range" and con.ext.serialization_format == "cdr"
    assert set(connections) == (
        set(TOPIC_TYPES) - {"/scan", "/imu/data_raw", "/imu/mag", "/actors/poses"}
    ) | {"/uwb/range"}
    types = get_types_from_msg(con.msgdef.data, con.msgtype)
    assert (
        types["sensor_msgs/msg/Range"] == humble.fielddefs["sensor_msgs/msg/Range"]
    )  # constants included
    embedded = get_typestore(Stores.EMPTY)
    embedded.register(types)
    assert embedded.hash_rihs01("sensor_msgs/msg/Range") == humble.hash_rihs01(
        "sensor_msgs/msg/Range"
    )


def test_uwb_ranges_decode_byte_exact_with_the_simulated_values(uwb_bag):
    from rosbags.typesys import Stores, get_typestore

    cfg, capture, _connections, raw = uwb_bag
    humble = get_typestore(Stores.ROS2_HUMBLE)
    ranges = [(t_ns, data) for topic, _type, t_ns, data in raw if topic == "/uwb/range"]
    src = capture.messages["uwb/range"]
    assert len(ranges) == len(src) >= 0.8 * cfg.uwb.rate_hz * len(cfg.uwb.anchors_x_m) * UWB_S
    frames = set()
    for (t_ns, data), (t_us, want) in zip(ranges, src):
        msg = humble.deserialize_cdr(data, "sensor_msgs/msg/Range")
        assert bytes(humble.serialize_cdr(msg, "sensor_msgs/msg/Range")) == data
        assert t_ns == t_us * 1000 == msg.header.stamp.sec * 10**9 + msg.header.stamp.nanosec
        assert msg.header.frame_id == want.header.frame_id
        assert msg.radiation_type == msg.INFRARED == want.radiation_type
        assert msg.range == np.float32(want.range)
        assert (msg.min_range, msg.max_range) == (
            np.float32(want.min_range),
            np.float32(want.max_range),
        )
        assert msg.field_of_view == pytest.approx(2 * math.pi, rel=1e-6)
        frames.add(msg.header.frame_id)
    assert frames == {f"uwb_anchor_{i}" for i in range(len(cfg.uwb.anchors_x_m))}
