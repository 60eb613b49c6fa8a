"""The twin on a real roscore, recorded by Debian's rosbag and read back with tools nobody here wrote:
``rosbag info``, the ``rosbags`` library, a tf2_ros buffer, Debian's robot_state_publisher.

One 20 s run with sensors (module fixture) at 5x real time, recorded while robot_state_publisher turns its
/joint_states into transforms on /rsp_tf (remapped, so that they can be told from the twin's own). At full
speed (18x to 50x real time here), and at 10x, rosbag record's subscriber queues overflow: it drops messages.
"""

import subprocess
import sys
import time
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pytest
import yaml

from conftest import ROOT, needs_ros1, stop

AMR_TWIN = str(Path(sys.executable).with_name("amr-twin"))
URDF = ROOT / "models" / "amr" / "amr.urdf"
TOPICS = ["/clock", "/tf", "/tf_static", "/odom", "/joint_states", "/scan", "/imu/data_raw", "/imu/mag",
          "/twin/ground_truth", "/wheel_Command", "/wheel0_Vel", "/wheel1_Vel", "/diagnostics", "/battery_state",
          "/rsp_tf"]
RUN_S = 20.0


def _rosparam_set(env, name: str, value: str) -> None:
    import xmlrpc.client

    xmlrpc.client.ServerProxy(env["ROS_MASTER_URI"]).setParam("/test", name, value)


@pytest.fixture(scope="module")
def bag(ros_env, tmp_path_factory):
    out = tmp_path_factory.mktemp("bag")
    _rosparam_set(ros_env, "/use_sim_time", True)
    _rosparam_set(ros_env, "/robot_description", URDF.read_text())
    rec = subprocess.Popen(["rosbag", "record", "-O", str(out / "run.bag"), *TOPICS, "__name:=test_record"],
                           env=ros_env, cwd=out, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    rsp = subprocess.Popen(["/usr/lib/robot_state_publisher/robot_state_publisher", "/tf:=/rsp_tf",
                            "/tf_static:=/rsp_tf_static", "__name:=test_rsp", "_publish_frequency:=1000.0"], env=ros_env,
                           stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        time.sleep(1.5)  # both subscribed before the twin starts
        run = subprocess.run([AMR_TWIN, "run", "linear", "--speed-m-s", "0.5", "--duration-s", str(RUN_S), "--world",
                              "empty", "--sensors", "--ros1", "--rate", "5", "--json"], env=ros_env, capture_output=True, text=True,
                             timeout=120)
        assert run.returncode == 0, run.stderr
        time.sleep(1.0)  # the last messages reach the recorder
    finally:
        stop(rsp)
        stop(rec)
    info = yaml.safe_load(subprocess.run(["rosbag", "info", "--yaml", str(out / "run.bag")], capture_output=True,
                                         text=True, env=ros_env, check=True).stdout)
    return out / "run.bag", info, run


def _counts(info) -> dict:
    return {t["topic"]: t["messages"] for t in info["topics"]}


def test_rosbag_info_shows_every_topic_at_its_rate_on_sim_time(bag):
    path, info, run = bag
    counts = _counts(info)
    # the node's rates: IMU 100 Hz, LiDAR 5.5 Hz, odometry and joint states 50 Hz, clock 100 Hz (t = 0..20 s)
    for topic, hz in (("/imu/data_raw", 100), ("/imu/mag", 100), ("/odom", 50), ("/joint_states", 50),
                      ("/clock", 100), ("/twin/ground_truth", 100), ("/battery_state", 10)):
        assert counts[topic] == int(RUN_S * hz) + 1, topic
    assert abs(counts["/scan"] - RUN_S * 5.5) <= 1.5
    assert counts["/tf_static"] == 1 and counts["/wheel_Command"] == 1
    assert counts["/wheel0_Vel"] >= 5 and counts["/diagnostics"] >= RUN_S  # the battery once a second
    # robot_state_publisher: one transform message per joint state it takes (its subscriber keeps one
    # message: at 5x real time it skips some)
    assert 0.3 * counts["/joint_states"] <= counts["/rsp_tf"] <= counts["/joint_states"]
    # the bag's time is the twin's simulated time (use_sim_time), not the wall clock's 2026
    # (the recorder's clock reads 0 until its first /clock: the first instants' messages take their times then)
    assert 0.0 <= info["start"] < 0.2 and abs(info["end"] - RUN_S) < 0.05
    assert info["duration"] == pytest.approx(RUN_S, abs=0.2)


def test_the_rosbags_library_reads_the_same_counts_and_the_mcaps_types(bag):
    from rosbags.highlevel import AnyReader

    path, info, _run = bag
    with AnyReader([path]) as reader:
        counts = {c.topic: c.msgcount for c in reader.connections}
        types = {c.topic: c.msgtype for c in reader.connections}
        scans = [reader.deserialize(raw, c.msgtype) for c, _t, raw in
                 reader.messages(connections=[c for c in reader.connections if c.topic == "/scan"])]
    assert counts == _counts(info)
    assert types["/scan"] == "sensor_msgs/msg/LaserScan" and types["/odom"] == "nav_msgs/msg/Odometry"
    assert types["/imu/data_raw"] == "sensor_msgs/msg/Imu" and types["/clock"] == "rosgraph_msgs/msg/Clock"
    assert types["/wheel0_Vel"] == "std_msgs/msg/Float64" and types["/diagnostics"] == "diagnostic_msgs/msg/DiagnosticArray"
    assert scans[0].header.frame_id == "laser" and len(scans[0].ranges) > 300
    assert scans[0].time_increment < 0  # the A1 spins clockwise (the recordings' convention)


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


pytestmark = [needs_ros1, pytest.mark.filterwarnings("ignore:(translation|rotation) should be of type")]


def test_a_tf2_buffer_from_the_bag_finds_every_urdf_frame_at_every_scan(bag):
    path, _info, _run = bag
    rospy, buf, scans, _rsp = _tf_buffer(path)
    links = [link.get("name") for link in ET.parse(URDF).getroot().iter("link")]
    assert len(links) == 10 and len(scans) >= 100
    for stamp in scans:
        for link in links:
            t = buf.lookup_transform("odom", link, stamp)  # raises if a frame is missing at that instant
            assert t.header.stamp == stamp
    # the laser sits on the robot: above the floor, where the URDF puts it
    laser = buf.lookup_transform("base_link", "laser", scans[-1]).transform.translation
    assert 0.2 < laser.z < 0.7


def test_robot_state_publisher_turns_the_joint_states_into_the_twins_wheel_transforms(bag):
    path, _info, _run = bag
    rospy, buf, _scans, rsp = _tf_buffer(path)
    wheels = [t for t in rsp if t.child_frame_id == "wheel_left_link"]
    assert len(wheels) >= 300 and all(t.header.frame_id == "base_link" for t in wheels)
    angles, offsets = [], []
    for t in wheels[::25]:
        mine = buf.lookup_transform("base_link", "wheel_left_link", t.header.stamp).transform
        theirs = t.transform
        offsets.append(np.subtract([theirs.translation.x, theirs.translation.y, theirs.translation.z],
                                   [mine.translation.x, mine.translation.y, mine.translation.z]))
        q1 = np.array([theirs.rotation.x, theirs.rotation.y, theirs.rotation.z, theirs.rotation.w])
        q2 = np.array([mine.rotation.x, mine.rotation.y, mine.rotation.z, mine.rotation.w])
        angles.append((2 * np.arccos(min(1.0, abs(q1 @ q2))), 2 * np.arccos(min(1.0, abs(q1[3])))))
    angles = np.array(angles)
    # the same wheel angle, from /joint_states through the URDF, as the twin's own link transform, within the
    # ~0.25 degree the twin's wheel tilts on its tyre spring (the left and right wheels' angles part by 0.4 rad
    # over this run, so a swap or a sign would show)
    assert angles[:, 0].max() < 0.01, angles[:, 0].max()
    assert angles[:, 1].max() > 1.0  # and the wheel turns: not the identity all along
    # the URDF's axle where the twin's wheel sits on its tyre spring, ~1 mm off
    assert np.abs(np.array(offsets)).max() < 3e-3


def _echo_once(env, topic: str, timeout_s: float = 30.0) -> dict:
    out = subprocess.run(["rostopic", "echo", "-n", "1", topic], env=env, capture_output=True, text=True,
                         timeout=timeout_s)
    assert out.returncode == 0, out.stderr
    return yaml.safe_load(out.stdout.split("---")[0])


def test_the_thesis_client_menu_drives_the_twin_through_the_real_service(ros_env, catkin_setup):
    import pexpect

    from conftest import in_workspace

    _rosparam_set(ros_env, "/use_sim_time", True)
    service = subprocess.Popen(in_workspace(catkin_setup, "rosrun amr_idea_control wheel_Command_Service"),
                               env=ros_env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    time.sleep(1.0)  # the service registered: the twin connects to it before it runs (Ros1Session.settle)
    twin = subprocess.Popen([AMR_TWIN, "run", "stop", "--duration-s", "40", "--world", "empty", "--ros1", "--rate", "4",
                             "--json"], env=ros_env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    command = subprocess.Popen(["rostopic", "echo", "-n", "1", "--filter", "m.data[1] > 0", "/wheel_Command"],
                               env=ros_env, stdout=subprocess.PIPE, text=True)  # not the twin's own stop at t = 0
    try:
        time.sleep(2.0)  # the service and the echo on the graph; the twin's own stop at t = 0 is behind us
        client = pexpect.spawn("bash", ["-c", f"source {catkin_setup} && rosrun amr_idea_control wheel_Command_Client"],
                               env=ros_env, encoding="utf-8", timeout=20)
        client.expect("choice: ")
        client.sendline("1")
        client.expect(r"linear speed \[m/s\]: ")
        client.sendline("0.7")
        client.expect(r"\(code (-?\d)\)")
        assert client.match.group(1) == "0"
        client.expect("choice: ")
        client.sendline("0")
        client.expect(pexpect.EOF)
        sent = yaml.safe_load(command.communicate(timeout=20)[0].split("---")[0])
        # listing 4.4: 0.7 m/s -> 0.7 * 60 / (0.25 pi) = 53.476 RPM, both wheels forward, float32 as the request
        assert sent["data"] == pytest.approx([1.0, 53.476, 1.0, 53.476], abs=1e-3)
        time.sleep(2.5)  # ~10 simulated s at 4x: the PI has settled
        speed = _echo_once(ros_env, "/wheel0_Vel")["data"]
        assert abs(speed - 53.476) <= 4.0  # the firmware's THRESHOLD_CONTROL
        out, err = twin.communicate(timeout=60)
        assert twin.returncode == 0, err
    finally:
        for proc in (command, twin):
            if proc.poll() is None:
                proc.kill()
        stop(service)
    import json

    wheels = json.loads(out)["wheels"]
    assert all(abs(wheels[w]["true_final_rpm"] - 53.476) < 4.0 for w in ("left", "right"))


def test_the_lidars_stop_motor_service_on_the_graph_stops_the_scans(ros_env, tmp_path):
    from rosbags.highlevel import AnyReader

    mcap = tmp_path / "run.mcap"
    twin = subprocess.Popen([AMR_TWIN, "run", "stop", "--duration-s", "12", "--world", "empty", "--sensors", "--ros1",
                             "--rate", "2", "--mcap", str(mcap)], env=ros_env, stdout=subprocess.DEVNULL,
                            stderr=subprocess.PIPE, text=True)
    try:
        twin.stderr.readline()  # "ros1: the twin is /amr_twin ...": on the graph
        time.sleep(1.0)
        call = subprocess.run(["rosservice", "call", "--wait", "/stop_motor"], env=ros_env, capture_output=True,
                              text=True, timeout=30)
        assert call.returncode == 0, call.stderr
        twin.wait(60)
    finally:
        if twin.poll() is None:
            twin.kill()
    assert twin.returncode == 0
    with AnyReader([mcap]) as reader:
        stamps = [t * 1e-9 for c, t, _raw in reader.messages(connections=[c for c in reader.connections
                                                                             if c.topic == "/scan"])]
    assert stamps and stamps[-1] < 9.0  # the motor stopped some seconds into the 12 s run: no scan after
    assert len(stamps) >= 5  # it scanned before (at 5.5 Hz)
