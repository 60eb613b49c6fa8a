"""``amr-twin run goto ... --ros1`` on a real roscore (amr_twin/ros1/navigation_setup.py,
``GoalsOnGraph``): the twin's navigator drives to ``--goal`` and is served as move_base; Debian's
``actionlib.SimpleActionClient`` (a process of its own) sends a goal on the way, which preempts
goto's: the run reports goto's goal PREEMPTED and the graph's reached (the true pose within the
tolerance), the action's result SUCCEEDED, and exits 0."""

import json
import math
import subprocess
import sys
from pathlib import Path

from conftest import needs_ros1, stop

AMR_TWIN = str(Path(sys.executable).with_name("amr-twin"))
START, GOTO, GRAPH = (-6.0, 0.0), (6.0, 0.0), (-2.0, 0.0)
"""In the warehouse's aisle along x: goto's goal 12 m ahead, the graph's 4 m ahead."""

CLIENT = """
import json, time
import rospy, actionlib
from move_base_msgs.msg import MoveBaseAction, MoveBaseGoal
from nav_msgs.msg import Odometry
rospy.set_param("/use_sim_time", True)
rospy.init_node("test_goto_graph")
truth = {}
rospy.Subscriber("/twin/ground_truth", Odometry,
                 lambda m: truth.update(x=m.pose.pose.position.x, v=m.twist.twist.linear.x),
                 queue_size=1)
client = actionlib.SimpleActionClient("move_base", MoveBaseAction)
client.wait_for_server()
end = time.monotonic() + 60
while not (truth.get("x", -99) > START[0] + 0.5 and truth["v"] > 0.2):  # goto's goal under way
    assert time.monotonic() < end, "timed out"
    time.sleep(0.02)
g = MoveBaseGoal()
g.target_pose.header.frame_id, g.target_pose.header.stamp = "map", rospy.Time.now()
g.target_pose.pose.position.x, g.target_pose.pose.position.y = GRAPH[0], GRAPH[1]
g.target_pose.pose.orientation.w = 1.0
sent_at = dict(truth)
client.send_goal(g)
client.wait_for_result()
print(json.dumps({"state": client.get_state(), "text": client.get_goal_status_text(),
                  "sent_at": sent_at}), flush=True)
"""


@needs_ros1
def test_a_graph_goal_preempts_gotos_and_is_reached(ros_env):
    script = f"START, GRAPH = {START}, {GRAPH}\n" + CLIENT
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
            "goto",
            "--world",
            "warehouse",
            f"--start={START[0]},{START[1]},0",
            "--goal",
            f"{GOTO[0]},{GOTO[1]}",
            "--localisation",
            "truth",
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
    try:
        out, err = client.communicate(timeout=90)
        assert client.returncode == 0, err
        twin_out, twin_err = twin.communicate(timeout=120)
    finally:
        stop(client)
        stop(twin)
    assert twin.returncode == 0, twin_err
    action = json.loads(out.splitlines()[-1])
    assert action["state"] == 3, action  # GoalStatus.SUCCEEDED
    assert action["sent_at"]["x"] < GRAPH[0] - 1.0, action  # sent well before the graph's goal
    run = json.loads(twin_out.splitlines()[-1])
    goals = [(tuple(g["goal"][:2]), g["status"]) for g in run["goals"]]
    assert goals == [(GOTO, "preempted"), (GRAPH, "succeeded")], goals
    x, y, _yaw = run["final_pose"]
    assert math.hypot(x - GRAPH[0], y - GRAPH[1]) <= 0.25, run[
        "final_pose"
    ]  # navigation.navigator.xy_tolerance_m
    assert "move_base on /move_base" in twin_err
