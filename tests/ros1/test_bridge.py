"""The twin on a real roscore, recorded by Debian's rosbag and read back with tools nobody here
wrote: ``rosbag info``, the ``rosbags`` library, a tf2_ros buffer, Debian's robot_state_publisher.

One 20 s run with sensors (module fixture) at 5x real time, recorded while robot_state_publisher
turns its /joint_states into transforms on /rsp_tf (remapped, so that they can be told from the
twin's own). At full speed, and at 10x, rosbag record's subscriber queues (100 messages a topic) can
overflow on a busy machine: it drops messages. At 5x it keeps every one (the counts below are
exact), provided it is connected before the twin runs and has read every byte before it is stopped:
the tests wait for both, never for a fixed time."""

import subprocess
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pytest
import yaml

from conftest import (
    ROOT,
    connected_subscribers,
    needs_ros1,
    stop,
    subscribers,
    wait_for,
    wait_until_recorded,
)

AMR_TWIN = str(Path(sys.executable).with_name("amr-twin"))
URDF = ROOT / "models" / "amr" / "amr.urdf"
TOPICS = [
    "/clock",
    "/tf",
    "/tf_static",
    "/odom",
    "/joint_states",
    "/scan",
    "/imu/data_raw",
    "/imu/mag",
    "/twin/ground_truth",
    "/wheel_Command",
    "/wheel0_Vel",
    "/wheel1_Vel",
    "/diagnostics",
    "/battery_state",
    "/rsp_tf",
    "/twin/true_rpm",
    "/twin/pwm_counts",
    "/twin/motor_current",
]
ROWS = {
    "/twin/true_rpm": "true_rpm",
    "/twin/pwm_counts": "pwm_counts",
    "/twin/motor_current": "current_a",
}
"""The row topics and their columns in the run's CSV."""
RUN_S = 20.0


def _rosparam_set(env, name: str, value: str) -> None:
    import xmlrpc.client

    xmlrpc.client.ServerProxy(env["ROS_MASTER_URI"]).setParam("/test", name, value)


@pytest.fixture(scope="module")
def bag(ros_env, tmp_path_factory):
    out = tmp_path_factory.mktemp("bag")
    _rosparam_set(ros_env, "/use_sim_time", True)
    _rosparam_set(ros_env, "/robot_description", URDF.read_text())
    rec = subprocess.Popen(
        ["rosbag", "record", "-O", str(out / "run.bag"), *TOPICS, "__name:=test_record"],
        env=ros_env,
        cwd=out,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    rsp = subprocess.Popen(
        [
            "/usr/lib/robot_state_publisher/robot_state_publisher",
            "/tf:=/rsp_tf",
            "/tf_static:=/rsp_tf_static",
            "__name:=test_rsp",
            "_publish_frequency:=1000.0",
        ],
        env=ros_env,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    try:
        # both on the graph before the twin starts (it then connects to them before it runs:
        # Ros1Session.settle), and the recorder connected to robot_state_publisher's output
        wait_for(
            lambda: (
                all("/test_record" in subscribers(ros_env, t) for t in TOPICS)
                and "/test_rsp" in subscribers(ros_env, "/joint_states")
                and "/test_record" in connected_subscribers(ros_env, "/test_rsp", "/rsp_tf")
            ),
            "rosbag record and robot_state_publisher on the graph",
        )
        run = subprocess.run(
            [
                AMR_TWIN,
                "run",
                "linear",
                "--speed-m-s",
                "0.5",
                "--duration-s",
                str(RUN_S),
                "--world",
                "empty",
                "--sensors",
                "--ros1",
                "--rate",
                "5",
                "--json",
                "--csv",
                str(out / "run.csv"),
            ],
            env=ros_env,
            capture_output=True,
            text=True,
            timeout=120,
        )
        assert run.returncode == 0, run.stderr
        wait_until_recorded(rec.pid)  # the twin's last messages are in the recorder
    finally:
        stop(rsp)
        stop(rec)
    done = subprocess.run(
        ["rosbag", "info", "--yaml", str(out / "run.bag")],
        capture_output=True,
        text=True,
        env=ros_env,
    )
    assert done.returncode == 0, (
        f"rosbag info: {done.stderr.strip()}; recorder exit {rec.returncode}; "
        f"files {sorted(p.name for p in out.iterdir())}"
    )
    info = yaml.safe_load(done.stdout)
    return out / "run.bag", info, run


def _counts(info) -> dict:
    return {t["topic"]: t["messages"] for t in info["topics"]}


def test_rosbag_info_shows_every_topic_at_its_rate_on_sim_time(bag):
    path, info, run = bag
    counts = _counts(info)
    # the node's rates: IMU 100 Hz, LiDAR 5.5 Hz, odometry and joint states 50 Hz, clock 100 Hz (t =
    # 0..20 s)
    for topic, hz in (
        ("/imu/data_raw", 100),
        ("/imu/mag", 100),
        ("/odom", 50),
        ("/joint_states", 50),
        ("/clock", 100),
        ("/twin/ground_truth", 100),
        ("/battery_state", 10),
        ("/twin/true_rpm", 100),
        ("/twin/pwm_counts", 100),
        ("/twin/motor_current", 100),
    ):
        assert counts[topic] == int(RUN_S * hz) + 1, topic
    assert abs(counts["/scan"] - RUN_S * 5.5) <= 1.5
    # odom -> base_link (odometry node) and the moving links, 50 Hz each; no map -> odom (no map in
    # the empty world: no localisation in map; test_tf_messages_by_frames tells them apart)
    assert counts["/tf"] == 2 * (int(RUN_S * 50) + 1)
    assert counts["/tf_static"] == 1 and counts["/wheel_Command"] == 1
    assert (
        counts["/wheel0_Vel"] >= 5 and counts["/diagnostics"] >= RUN_S
    )  # the battery once a second
    # robot_state_publisher: at most one transform message per joint state it takes; its subscriber
    # keeps one message (queue size 1), so how many of the 1001 it takes depends on the CPU it gets,
    # not on the twin
    assert 1 <= counts["/rsp_tf"] <= counts["/joint_states"]
    # the bag's time is the twin's simulated time (use_sim_time), not the wall clock's 2026
    # (the recorder's clock reads 0 until its first /clock: the first instants' messages take their
    # times then)
    assert 0.0 <= info["start"] < 0.2 and abs(info["end"] - RUN_S) < 0.05
    assert info["duration"] == pytest.approx(RUN_S, abs=0.2)


def test_the_rosbags_library_reads_the_same_counts_and_the_mcaps_types(bag):
    from rosbags.highlevel import AnyReader

    path, info, _run = bag
    with AnyReader([path]) as reader:
        counts = {c.topic: c.msgcount for c in reader.connections}
        types = {c.topic: c.msgtype for c in reader.connections}
        scans = [
            reader.deserialize(raw, c.msgtype)
            for c, _t, raw in reader.messages(
                connections=[c for c in reader.connections if c.topic == "/scan"]
            )
        ]
    assert counts == _counts(info)
    assert (
        types["/scan"] == "sensor_msgs/msg/LaserScan" and types["/odom"] == "nav_msgs/msg/Odometry"
    )
    assert (
        types["/imu/data_raw"] == "sensor_msgs/msg/Imu"
        and types["/clock"] == "rosgraph_msgs/msg/Clock"
    )
    assert (
        types["/wheel0_Vel"] == "std_msgs/msg/Float64"
        and types["/diagnostics"] == "diagnostic_msgs/msg/DiagnosticArray"
    )
    assert scans[0].header.frame_id == "laser" and len(scans[0].ranges) > 300
    assert scans[0].time_increment < 0  # the A1 spins clockwise (the recordings' convention)


def test_every_instant_is_recorded_once_and_in_order_and_the_rows_are_the_csvs(bag):
    """Stamped topics: one message an instant of their period from 0 to the end, in stamp order; the
    row topics (no stamps): the run's CSV columns, row by row (read with the rosbags library)."""
    from rosbags.highlevel import AnyReader

    path, _info, _run = bag
    stamped = ("/clock", "/twin/ground_truth", "/joint_states", "/battery_state", "/imu/data_raw")
    stamps, rows = {topic: [] for topic in stamped}, {topic: [] for topic in ROWS}
    with AnyReader([path]) as reader:
        for c, _t, raw in reader.messages(
            connections=[c for c in reader.connections if c.topic in (*stamped, *ROWS)]
        ):
            msg = reader.deserialize(raw, c.msgtype)
            if c.topic in ROWS:
                rows[c.topic].append(list(msg.data))
            else:
                stamp = msg.clock if c.topic == "/clock" else msg.header.stamp
                stamps[c.topic].append(stamp.sec * 1_000_000 + stamp.nanosec // 1000)
    for topic, period_us in (
        ("/clock", 10_000),
        ("/twin/ground_truth", 10_000),
        ("/imu/data_raw", 10_000),
        ("/joint_states", 20_000),
        ("/battery_state", 100_000),
    ):
        assert stamps[topic] == list(range(0, int(RUN_S * 1e6) + 1, period_us)), topic
    csv = np.genfromtxt(
        path.with_name("run.csv"), delimiter=",", names=True, skip_header=1
    )  # under the note
    assert len(csv) == int(RUN_S * 100) + 1
    for topic, column in ROWS.items():
        want = np.column_stack([csv[f"{column}_left"], csv[f"{column}_right"]])
        np.testing.assert_allclose(
            np.array(rows[topic]), want, rtol=1e-8, atol=1e-12, err_msg=topic
        )


def _tf_buffer(path):
    from amr_twin.ros1.installation import import_rospy

    rospy = import_rospy()
    import rosbag
    import tf2_ros

    buf = tf2_ros.Buffer(cache_time=rospy.Duration(3600), debug=False)
    scans, rsp = [], []
    with rosbag.Bag(str(path)) as b:
        for topic, msg, _t in b.read_messages(topics=["/tf", "/tf_static", "/scan", "/rsp_tf"]):
            if topic == "/scan":
                scans.append(msg.header.stamp)
            elif topic == "/rsp_tf":
                rsp.extend(msg.transforms)
            else:
                for ts in msg.transforms:
                    if topic == "/tf_static":
                        buf.set_transform_static(ts, "bag")
                    else:
                        buf.set_transform(ts, "bag")
    return rospy, buf, scans, rsp


pytestmark = [
    needs_ros1,
    pytest.mark.filterwarnings("ignore:(translation|rotation) should be of type"),
]


def test_tf_messages_by_frames(bag):
    """/tf: one odom -> base_link message at each 50 Hz instant (the odometry node), one of the
    moving links (the bridge's joint states), no map -> odom (the empty world has no map, so no
    localisation in map)."""
    from amr_twin.ros1.installation import import_rospy

    import_rospy()
    import rosbag

    path, _info, _run = bag
    kinds: dict = {}
    with rosbag.Bag(str(path)) as b:
        for _topic, msg, _t in b.read_messages(topics=["/tf"]):
            pairs = {(ts.header.frame_id, ts.child_frame_id) for ts in msg.transforms}
            key = (
                ("odom", "base_link")
                if ("odom", "base_link") in pairs
                else (("map", "odom") if ("map", "odom") in pairs else "links")
            )
            assert key == "links" or len(pairs) == 1, pairs
            kinds[key] = kinds.get(key, 0) + 1
    assert kinds == {("odom", "base_link"): int(RUN_S * 50) + 1, "links": int(RUN_S * 50) + 1}, (
        kinds
    )


def test_a_tf2_buffer_from_the_bag_finds_every_urdf_frame_at_every_scan(bag):
    path, _info, _run = bag
    rospy, buf, scans, _rsp = _tf_buffer(path)
    links = [link.get("name") for link in ET.parse(URDF).getroot().iter("link")]
    assert len(links) == 10 and len(scans) >= 100
    for stamp in scans:
        for link in links:
            t = buf.lookup_transform(
                "odom", link, stamp
            )  # raises if a frame is missing at that instant
            assert t.header.stamp == stamp
    # the laser sits on the robot: above the floor, where the URDF puts it
    laser = buf.lookup_transform("base_link", "laser", scans[-1]).transform.translation
    assert 0.2 < laser.z < 0.7


def test_robot_state_publisher_turns_the_joint_states_into_the_twins_wheel_transforms(bag):
    path, _info, _run = bag
    rospy, buf, _scans, rsp = _tf_buffer(path)
    import rosbag

    with rosbag.Bag(str(path)) as b:
        joint_stamps = {
            msg.header.stamp for _topic, msg, _t in b.read_messages(topics=["/joint_states"])
        }
    wheels = [t for t in rsp if t.child_frame_id == "wheel_left_link"]
    # robot_state_publisher keeps one joint state at a time (queue size 1): it takes as many of the
    # 1001 as the CPU it gets allows, each at that joint state's stamp; on any machine some, across
    # the whole run
    assert len(wheels) >= 10 and all(t.header.frame_id == "base_link" for t in wheels)
    assert all(t.header.stamp in joint_stamps for t in wheels)
    seen = sorted(t.header.stamp.to_sec() for t in wheels)
    assert seen[0] < 0.25 * RUN_S and seen[-1] > 0.75 * RUN_S, seen
    angles, offsets = [], []
    for t in wheels:
        mine = buf.lookup_transform("base_link", "wheel_left_link", t.header.stamp).transform
        theirs = t.transform
        offsets.append(
            np.subtract(
                [theirs.translation.x, theirs.translation.y, theirs.translation.z],
                [mine.translation.x, mine.translation.y, mine.translation.z],
            )
        )
        q1 = np.array([theirs.rotation.x, theirs.rotation.y, theirs.rotation.z, theirs.rotation.w])
        q2 = np.array([mine.rotation.x, mine.rotation.y, mine.rotation.z, mine.rotation.w])
        angles.append((2 * np.arccos(min(1.0, abs(q1 @ q2))), 2 * np.arccos(min(1.0, abs(q1[3])))))
    angles = np.array(angles)
    # the same wheel angle, from /joint_states through the URDF, as the twin's own link transform,
    # within the ~0.25 degree the twin's wheel tilts on its tyre spring (the left and right wheels'
    # angles part by 0.4 rad over this run, so a swap or a sign would show)
    assert angles[:, 0].max() < 0.01, angles[:, 0].max()
    assert angles[:, 1].max() > 1.0  # and the wheel turns: not the identity all along
    # the URDF's axle where the twin's wheel sits on its tyre spring, ~1 mm off
    assert np.abs(np.array(offsets)).max() < 3e-3


SPEEDS = """
import rospy
from std_msgs.msg import Float64
rospy.init_node("test_speeds")
rospy.Subscriber("/wheel0_Vel", Float64,
                 lambda m: print(rospy.get_rostime().to_sec(), m.data, flush=True))
rospy.spin()
"""


def test_the_thesis_client_menu_drives_the_twin_through_the_real_service(ros_env, catkin_setup):
    import json

    import pexpect

    from conftest import in_workspace

    _rosparam_set(ros_env, "/use_sim_time", True)
    service = subprocess.Popen(
        in_workspace(catkin_setup, "rosrun amr_idea_control wheel_Command_Service"),
        env=ros_env,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    command = subprocess.Popen(
        ["rostopic", "echo", "-n", "1", "--filter", "m.data[1] > 0", "/wheel_Command"],
        env=ros_env,
        stdout=subprocess.PIPE,
        text=True,
    )  # not the twin's own stop at t = 0
    # each speed the firmware publishes, with the simulated time it arrived (Debian's rospy;
    # rostopic would not subscribe before someone publishes the topic)
    speeds = subprocess.Popen(
        ["/usr/bin/python3", "-c", SPEEDS], env=ros_env, stdout=subprocess.PIPE, text=True
    )
    twin = client = None
    try:
        # everything on the graph and waiting before the twin starts: the service with the echo
        # connected to its wheel_Command, the speed echo subscribed (the twin connects to it before
        # it runs), the client's menu
        client = pexpect.spawn(
            "bash",
            ["-c", f"source {catkin_setup} && rosrun amr_idea_control wheel_Command_Client"],
            env=ros_env,
            encoding="utf-8",
            timeout=60,
        )
        client.expect("choice: ")
        wait_for(
            lambda: (
                any(
                    n.startswith("/rostopic")
                    for n in connected_subscribers(
                        ros_env, "/wheel_Command_Service", "/wheel_Command"
                    )
                )
                and "/test_speeds" in subscribers(ros_env, "/wheel0_Vel")
            ),
            "the service, the echo and the speed listener on the graph",
        )
        twin = subprocess.Popen(
            [
                AMR_TWIN,
                "run",
                "stop",
                "--duration-s",
                "40",
                "--world",
                "empty",
                "--ros1",
                "--rate",
                "4",
                "--json",
            ],
            env=ros_env,
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
        )
        wait_for(
            lambda: (
                "/amr_twin"
                in connected_subscribers(ros_env, "/wheel_Command_Service", "/wheel_Command")
            ),
            "the twin connected to the service's wheel_Command",
        )
        client.sendline("1")
        client.expect(r"linear speed \[m/s\]: ")
        client.sendline("0.7")
        client.expect(r"\(code (-?\d)\)")
        assert client.match.group(1) == "0"
        client.expect("choice: ")
        client.sendline("0")
        client.expect(pexpect.EOF)
        sent = yaml.safe_load(command.communicate(timeout=60)[0].split("---")[0])
        # listing 4.4: 0.7 m/s -> 0.7 * 60 / (0.25 pi) = 53.476 RPM, both wheels forward, float32 as
        # the request
        assert sent["data"] == pytest.approx([1.0, 53.476, 1.0, 53.476], abs=1e-3)
        out, err = twin.communicate(timeout=120)
        assert twin.returncode == 0, err
    finally:
        for proc in (command, twin):
            if proc is not None and proc.poll() is None:
                proc.kill()
        if client is not None:
            client.close(force=True)
        stop(service)
        stop(speeds)
    rows = [line.split() for line in speeds.communicate(timeout=30)[0].splitlines() if line.strip()]
    t_s, rpm = np.array([float(t) for t, _v in rows]), np.array([float(v) for _t, v in rows])
    # the firmware publishes |RPM| once a revolution from the command on (t_s[0]); from 10 simulated
    # s later the PI has settled: every speed it publishes is within its THRESHOLD_CONTROL (4 RPM)
    # of 53.476
    settled = rpm[t_s > t_s[0] + 10.0]
    assert len(settled) >= 5, (t_s, rpm)
    assert np.all(np.abs(settled - 53.476) <= 4.0), settled
    wheels = json.loads(out)["wheels"]
    assert all(abs(wheels[w]["true_final_rpm"] - 53.476) < 4.0 for w in ("left", "right"))


STOP_MOTOR = """
import rospy
from std_srvs.srv import Empty
rospy.init_node("test_stop_motor")
print("ready", flush=True)
rospy.wait_for_service("/stop_motor")
while rospy.get_rostime().to_sec() < 2.0:  # simulated time: some scans first
    rospy.sleep(0.01)
t0 = rospy.get_rostime().to_sec()
rospy.ServiceProxy("/stop_motor", Empty)()
rospy.sleep(0.05)  # the clock of the instant the call acted has come
print(t0, rospy.get_rostime().to_sec(), flush=True)
"""


def test_the_lidars_stop_motor_service_on_the_graph_stops_the_scans(ros_env, tmp_path):
    from rosbags.highlevel import AnyReader

    _rosparam_set(ros_env, "/use_sim_time", True)
    mcap = tmp_path / "run.mcap"
    # the caller (Debian's rospy) is on the graph first, and calls 2 simulated s into the run
    caller = subprocess.Popen(
        ["/usr/bin/python3", "-c", STOP_MOTOR], env=ros_env, stdout=subprocess.PIPE, text=True
    )
    twin = None
    try:
        assert caller.stdout.readline().strip() == "ready"
        wait_for(
            lambda: "/test_stop_motor" in subscribers(ros_env, "/clock"),
            "the caller subscribed to /clock",
        )
        twin = subprocess.Popen(
            [
                AMR_TWIN,
                "run",
                "stop",
                "--duration-s",
                "12",
                "--world",
                "empty",
                "--sensors",
                "--ros1",
                "--rate",
                "2",
                "--mcap",
                str(mcap),
            ],
            env=ros_env,
            stdout=subprocess.DEVNULL,
            stderr=subprocess.PIPE,
            text=True,
        )
        t0, t1 = map(float, caller.communicate(timeout=120)[0].split())
        _out, err = twin.communicate(timeout=120)
        assert twin.returncode == 0, err
    finally:
        for proc in (caller, twin):
            if proc is not None and proc.poll() is None:
                proc.kill()
    with AnyReader([mcap]) as reader:
        stamps = np.array(
            [
                t * 1e-9
                for c, t, _raw in reader.messages(
                    connections=[c for c in reader.connections if c.topic == "/scan"]
                )
            ]
        )
    assert (
        2.0 <= t0 <= t1 <= 10.0
    )  # the call acted between t0 and t1, 2 s or more before the run's end (12 s)
    assert len(stamps) >= 5 and stamps.max() >= t0 - 0.2  # it scanned at 5.5 Hz until the call ...
    assert stamps.max() <= t1  # ... and not after it: no scan in the 2 s or more left
