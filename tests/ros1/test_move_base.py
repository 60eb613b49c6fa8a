"""The navigator on a real ROS 1 graph as move_base (amr_twin/ros1/navigation_server.py): a standard
``actionlib.SimpleActionClient('move_base', MoveBaseAction)`` (Debian's, a process of its own)
drives ``amr-twin run stop --world warehouse --sensors --ros1`` from ``--start=-6,0,0``. One run, in
order: a goal in frame ``odom`` (refused), a goal 4 m ahead (reached: the twin's ground truth within
the navigator's tolerance), a far goal canceled on the way (PREEMPTED, the robot stops), a goal
inside a rack (ABORTED with the reason), a pose on ``move_base_simple/goal`` (reached, on the
action's result topic)."""

import json
import math
import subprocess
import sys
from pathlib import Path

import pytest

from conftest import needs_ros1, stop

AMR_TWIN = str(Path(sys.executable).with_name("amr-twin"))
AHEAD = (-2.0, 0.0)
"""4 m ahead of the start (-6, 0, 0 deg), in the aisle along x."""
IN_RACK = (0.0, 3.0)
"""Inside the rack row at y 2.8-3.3 m."""
FAR = (6.0, 0.0)
SIMPLE = (-3.0, 0.0)

CLIENT = """
import json, math, sys, time
import rospy, actionlib
from actionlib_msgs.msg import GoalStatus
from geometry_msgs.msg import PoseStamped
from move_base_msgs.msg import MoveBaseAction, MoveBaseActionResult, MoveBaseGoal
from nav_msgs.msg import Odometry
from tf2_msgs.msg import TFMessage
import tf2_ros
rospy.set_param("/use_sim_time", True)
rospy.init_node("test_move_base")
tf_buffer = tf2_ros.Buffer()
tf_listener = tf2_ros.TransformListener(tf_buffer)
map_odom = []
def on_tf(m):
    map_odom.extend(t.header.stamp.to_sec() for t in m.transforms
                    if t.header.frame_id == "map" and t.child_frame_id == "odom")
rospy.Subscriber("/tf", TFMessage, on_tf, queue_size=1000)
truth, results, feedback = {}, [], []
def on_truth(m):
    truth.update(x=m.pose.pose.position.x, y=m.pose.pose.position.y, v=m.twist.twist.linear.x,
                 w=m.twist.twist.angular.z, t=m.header.stamp.to_sec())
rospy.Subscriber("/twin/ground_truth", Odometry, on_truth, queue_size=1)
rospy.Subscriber("/move_base/result", MoveBaseActionResult,
                 lambda m: results.append((m.status.status, m.status.text)))
simple = rospy.Publisher("/move_base_simple/goal", PoseStamped, queue_size=1)
client = actionlib.SimpleActionClient("move_base", MoveBaseAction)
client.wait_for_server()
out = {"server_t": rospy.get_time()}
def goal(x, y, frame="map"):
    g = MoveBaseGoal()
    g.target_pose.header.frame_id, g.target_pose.header.stamp = frame, rospy.Time.now()
    g.target_pose.pose.position.x, g.target_pose.pose.position.y = x, y
    g.target_pose.pose.orientation.w = 1.0
    return g
def until(cond, wall_s=60.0):
    end = time.monotonic() + wall_s
    while not cond():
        assert time.monotonic() < end, "timed out"
        time.sleep(0.02)
def done():
    return {"state": client.get_state(), "text": client.get_goal_status_text()}
client.send_goal(goal(*AHEAD, frame="odom"))
client.wait_for_result()
out["odom_frame"] = done()
t0, wall0 = rospy.get_time(), time.monotonic()
client.send_goal(goal(*AHEAD),
                 feedback_cb=lambda f: feedback.append(f.base_position.header.frame_id))
client.wait_for_result()
out["ahead"] = dict(done(), sim_s=rospy.get_time() - t0, wall_s=time.monotonic() - wall0,
                    feedback=feedback[:1], n_feedback=len(feedback))
rospy.sleep(1.0)
out["ahead"]["truth"] = dict(truth)
try:
    tr = tf_buffer.lookup_transform("map", "base_link", rospy.Time(0), rospy.Duration(5.0))
    out["ahead"]["tf"] = {"x": tr.transform.translation.x, "y": tr.transform.translation.y}
except tf2_ros.TransformException as exc:
    out["ahead"]["tf"] = str(exc)
out["map_odom"] = {"n": len(map_odom), "first": min(map_odom, default=0),
                   "last": max(map_odom, default=0)}
client.send_goal(goal(*FAR))
until(lambda: truth["x"] > AHEAD[0] + 1.0 and truth["v"] > 0.2)
out["moving"] = dict(truth)
client.cancel_goal()
client.wait_for_result()
out["cancel"] = done()
rospy.sleep(2.0)
out["after_cancel"] = dict(truth)
rospy.sleep(1.0)
out["later"] = dict(truth)
before, t0 = dict(truth), rospy.get_time()
client.send_goal(goal(*IN_RACK))
client.wait_for_result()
out["rack"] = dict(done(), sim_s=rospy.get_time() - t0)
rospy.sleep(1.0)
out["rack"]["moved_m"] = math.hypot(truth["x"] - before["x"], truth["y"] - before["y"])
until(lambda: simple.get_num_connections() > 0)
n = len(results)
p = PoseStamped()
p.header.frame_id, p.header.stamp = "map", rospy.Time.now()
p.pose.position.x, p.pose.position.y, p.pose.orientation.w = SIMPLE[0], SIMPLE[1], 1.0
simple.publish(p)
until(lambda: len(results) > n)
rospy.sleep(1.0)
out["simple"] = {"result": results[n], "truth": dict(truth)}
print(json.dumps(out), flush=True)
"""


@pytest.fixture(scope="module")
def session(ros_env):
    script = (f"AHEAD, FAR, IN_RACK, SIMPLE = {AHEAD}, {FAR}, {IN_RACK}, {SIMPLE}\n") + CLIENT
    client = subprocess.Popen(
        ["/usr/bin/python3", "-c", script],
        env=ros_env,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    twin = subprocess.Popen(
        [
            AMR_TWIN,
            "run",
            "stop",
            "--duration-s",
            "60",
            "--world",
            "warehouse",
            "--sensors",
            "--ros1",
            "--start=-6,0,0",
            "--rate",
            "4",
        ],
        env=ros_env,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        out, err = client.communicate(timeout=240)
        assert client.returncode == 0, err
        twin_out, twin_err = twin.communicate(timeout=120)
        assert twin.returncode == 0, twin_err
    finally:
        stop(client)
        stop(twin)
    return json.loads(out.splitlines()[-1]), twin_err


def _tolerance_m() -> float:
    from amr_twin.model.config import load_config

    return load_config().navigation.navigator.xy_tolerance_m


@needs_ros1
def test_a_goal_ahead_ends_succeeded_with_the_true_pose_within_the_tolerance(session):
    got, _err = session
    ahead = got["ahead"]
    assert ahead["state"] == 3, ahead  # GoalStatus.SUCCEEDED
    assert (
        ahead["feedback"] == ["map"] and ahead["n_feedback"] >= 10
    )  # the base pose, in map, at 10 Hz simulated
    truth = ahead["truth"]
    assert math.hypot(truth["x"] - AHEAD[0], truth["y"] - AHEAD[1]) <= _tolerance_m(), truth
    assert abs(truth["v"]) < 0.01, truth  # it stands there
    print(
        f"time to goal: {ahead['sim_s']:.2f} s simulated ({ahead['wall_s']:.2f} s wall at --rate 4)"
    )


@needs_ros1
def test_tf2_resolves_map_to_base_link_through_map_to_odom_at_25_hz(session):
    """The EKF's map -> odom composed with the odometry's odom -> base_link (a tf2_ros buffer of the
    client) is where the robot stands, within the EKF's error; map -> odom came at 25 Hz of
    simulated time."""
    got, _err = session
    tf, truth = got["ahead"]["tf"], got["ahead"]["truth"]
    assert isinstance(tf, dict), tf  # the lookup's error otherwise
    print(f"map -> base_link {tf}, truth {truth}, map -> odom {got['map_odom']}")
    assert math.hypot(tf["x"] - truth["x"], tf["y"] - truth["y"]) < 0.1, (tf, truth)
    m = got["map_odom"]
    assert m["last"] - m["first"] > 5.0, m
    assert (m["n"] - 1) / (m["last"] - m["first"]) == pytest.approx(25.0, abs=0.5), m


@needs_ros1
def test_a_goal_in_another_frame_and_one_in_a_rack_end_aborted_saying_why(session):
    got, _err = session
    assert got["odom_frame"]["state"] == 4, got["odom_frame"]  # GoalStatus.ABORTED
    assert "frame_id 'odom'" in got["odom_frame"]["text"] and "'map'" in got["odom_frame"]["text"]
    rack = got["rack"]
    assert rack["state"] == 4, rack
    assert "(0.00, 3.00) lies inside an obstacle" in rack["text"]
    # refused at once, from the map: the navigator's recoveries (spin, wait, back up) would take
    # seconds
    assert rack["sim_s"] <= 0.5 and rack["moved_m"] < 0.01, rack


@needs_ros1
def test_a_cancel_ends_preempted_and_the_robot_stops(session):
    got, _err = session
    assert got["cancel"]["state"] == 2, got["cancel"]  # GoalStatus.PREEMPTED
    after, later = got["after_cancel"], got["later"]
    assert abs(after["v"]) < 0.01 and abs(after["w"]) < 0.01, after
    assert math.hypot(later["x"] - after["x"], later["y"] - after["y"]) < 0.01
    assert after["x"] < FAR[0] - 3.0  # stopped far from the canceled goal


@needs_ros1
def test_a_pose_on_move_base_simple_goal_is_a_goal_of_the_action(session):
    got, _err = session
    status, _text = got["simple"]["result"]
    assert status == 3, got["simple"]
    truth = got["simple"]["truth"]
    assert math.hypot(truth["x"] - SIMPLE[0], truth["y"] - SIMPLE[1]) <= _tolerance_m(), truth
