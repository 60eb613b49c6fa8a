"""A fleet's .mcap read back with the mcap library and its ROS 2 decoder: every robot's topics
under its namespace, its frames prefixed on the one /tf, one /clock, the counts alike."""

import collections

import pytest

from fleet_run import DURATION_S, STARTS, record_fleet

ROBOTS = [f"amr-{i}" for i in range(1, len(STARTS) + 1)]
PER_ROBOT = (
    "odom",
    "scan",
    "imu/data_raw",
    "imu/mag",
    "wheel0_Vel",
    "wheel1_Vel",
    "odometry/filtered",
    "twin/ground_truth",
    "twin/true_rpm",
    "twin/pwm_counts",
    "twin/motor_current",
    "battery_state",
    "joint_states",
    "robot_description",
)
"""Topics each standing robot of the fixture publishes, under /<name>/."""


@pytest.fixture(scope="module")
def recorded(tmp_path_factory):
    return record_fleet(tmp_path_factory.mktemp("fleet"))


@pytest.fixture(scope="module")
def messages(recorded):
    from mcap.reader import make_reader
    from mcap_ros2.decoder import DecoderFactory

    out = collections.defaultdict(list)
    with open(recorded[1], "rb") as f:
        reader = make_reader(f, decoder_factories=[DecoderFactory()])
        for _schema, channel, message, msg in reader.iter_decoded_messages():  # every channel
            out[channel.topic].append((message.log_time, msg))
    return out


def test_every_robot_under_its_namespace_and_nothing_outside(messages):
    for name in ROBOTS:
        missing = [t for t in PER_ROBOT if f"/{name}/{t}" not in messages]
        assert not missing, (name, missing)
    outside = {t for t in messages if not t.startswith(tuple(f"/{n}/" for n in ROBOTS))}
    assert outside == {"/clock", "/tf", "/tf_static"}


def test_counts_per_robot_alike(messages):
    n_clock = len(messages["/clock"])
    assert n_clock == int(DURATION_S * 100) + 1  # the 100 Hz grid, once for the world
    for topic in ("twin/ground_truth", "twin/true_rpm", "joint_states", "odom", "imu/data_raw"):
        counts = [len(messages[f"/{name}/{topic}"]) for name in ROBOTS]
        assert len(set(counts)) == 1 and counts[0] > 0, (topic, counts)
    scans = [len(messages[f"/{name}/scan"]) for name in ROBOTS]
    assert max(scans) - min(scans) <= 1 and min(scans) >= 5 * DURATION_S, scans


def test_each_robots_ground_truth_where_it_stands(messages):
    for name, (x, y, _yaw) in zip(ROBOTS, STARTS):
        _t, odom = messages[f"/{name}/twin/ground_truth"][-1]
        p = odom.pose.pose.position
        assert (odom.header.frame_id, odom.child_frame_id) == ("world", f"{name}/base_link")
        assert abs(p.x - x) < 0.02 and abs(p.y - y) < 0.02, (name, p)


def test_one_tf_tree_with_each_robots_frames(messages):
    edges = {
        (tf.header.frame_id, tf.child_frame_id)
        for topic in ("/tf", "/tf_static")
        for _t, msg in messages[topic]
        for tf in msg.transforms
    }
    for name in ROBOTS:
        for edge in (
            ("map", f"{name}/odom"),
            (f"{name}/odom", f"{name}/base_link"),
            (f"{name}/base_link", f"{name}/laser"),
            (f"{name}/base_link", f"{name}/wheel_left_link"),
        ):
            assert edge in edges, edge
    parents = collections.Counter(child for _parent, child in edges)
    assert max(parents.values()) == 1  # every frame one parent: one tree
    shared = {"map", "world"}
    for parent, child in edges:
        for frame in (parent, child):
            assert frame in shared or frame.startswith(("uwb_anchor_", *(n + "/" for n in ROBOTS)))
    _t, scan = messages["/amr-2/scan"][0]
    assert scan.header.frame_id == "amr-2/laser"
