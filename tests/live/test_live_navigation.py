"""``amr-twin run goto --live``: the plan, the map, the costmap and the footprint reach a Foxglove
client."""

import json
import math
import re
import sys
from pathlib import Path

import pytest

from foxglove_client import FoxgloveClient, start_cli

AMR_TWIN = str(Path(sys.executable).with_name("amr-twin"))
TOPICS = {
    "/plan": "nav_msgs/msg/Path",
    "/map": "nav_msgs/msg/OccupancyGrid",
    "/local_costmap/costmap": "nav_msgs/msg/OccupancyGrid",
    "/local_costmap/published_footprint": "geometry_msgs/msg/PolygonStamped",
}


def test_goto_live_serves_the_plan_map_costmap_and_footprint():
    proc, url = start_cli(
        [
            "run",
            "goto",
            "--goal",
            "-6,0,180",
            "--start=-9,0,0",
            "--localisation",
            "truth",
            "--live",
            "--port",
            "0",
            "--rate",
            "0",
        ],
        AMR_TWIN,
    )
    try:
        with FoxgloveClient(url) as client:
            client.wait_for_channels(list(TOPICS), timeout_s=30.0)
            assert {t: client.channels[t]["schemaName"] for t in TOPICS} == TOPICS
            client.subscribe(list(TOPICS))
            got = client.pump(20.0, until=lambda: client.closed)
    finally:
        out, err = proc.communicate(timeout=120)
    assert proc.returncode == 0, err[-2000:]
    seen = {topic for _t, topic, _ns, _payload in got}
    assert {"/plan", "/local_costmap/published_footprint", "/local_costmap/costmap"} <= seen, seen


def _pose_stamped(frame: str, x: float, y: float, yaw: float) -> bytes:
    from rosbags.typesys import Stores, get_typestore

    ts = get_typestore(Stores.ROS2_HUMBLE)
    T = ts.types
    msg = T["geometry_msgs/msg/PoseStamped"](
        header=T["std_msgs/msg/Header"](
            stamp=T["builtin_interfaces/msg/Time"](sec=0, nanosec=0), frame_id=frame
        ),
        pose=T["geometry_msgs/msg/Pose"](
            position=T["geometry_msgs/msg/Point"](x=x, y=y, z=0.0),
            orientation=T["geometry_msgs/msg/Quaternion"](
                x=0.0, y=0.0, z=math.sin(yaw / 2), w=math.cos(yaw / 2)
            ),
        ),
    )
    return ts.serialize_cdr(msg, "geometry_msgs/msg/PoseStamped")


def test_a_goal_published_on_goal_pose_preempts_the_running_goal():
    """Foxglove's publish tools: the server advertises /goal_pose (geometry_msgs/msg/PoseStamped); a
    client's goal in the odom frame (the start pose: 4 m ahead, turned to 90 deg) replaces the goal
    35 m away; the robot stops there."""
    proc, url = start_cli(
        [
            "run",
            "goto",
            "--world",
            "aisles",
            "--goal",
            "15,-4.8",
            "--start=-20,-4.8,0",
            "--localisation",
            "truth",
            "--controller",
            "rpp",
            "--live",
            "--port",
            "0",
            "--rate",
            "2",
            "--json",
        ],
        AMR_TWIN,
    )
    try:
        with FoxgloveClient(url) as client:
            client.wait_for_channels(["/goal_pose", "/plan"], timeout_s=30.0)
            assert client.channels["/goal_pose"]["schemaName"] == "geometry_msgs/msg/PoseStamped"
            client.subscribe(["/goal_pose", "/plan"])
            got = []
            client.pump(
                30.0, got, until=lambda: any(topic == "/plan" for _t, topic, _ns, _p in got)
            )
            channel = client.advertise("/goal_pose", "geometry_msgs/msg/PoseStamped")
            client.publish(channel, _pose_stamped("odom", 4.0, 0.0, math.pi / 2))
            client.pump(60.0, got, until=lambda: client.closed)
    finally:
        out, err = proc.communicate(timeout=120)
    assert proc.returncode == 0, err[-2000:]
    info = json.loads(out)
    first, second = info["goals"]
    assert first["status"] == "preempted" and second["status"] == "succeeded", info["goals"]
    assert second["goal"] == pytest.approx([-16.0, -4.8, 90.0])
    x, y, yaw = info["final_pose"]
    assert (
        math.hypot(x + 16.0, y + 4.8) <= 0.25
        and abs(math.remainder(yaw - math.pi / 2, 2 * math.pi)) <= 0.25
    )
    assert any(
        topic == "/goal_pose" for _t, topic, _ns, _p in got
    )  # the goal taken, echoed to the clients


@pytest.mark.parametrize(
    "frame, x, why",
    [
        ("base_link", 1.0, "goal_pose in frame 'base_link': give it in map or odom"),
        ("map", float("nan"), "pose.position.x=nan: must be a finite number"),
        ("map", 2e4, "each coordinate must be within +-10000 m"),
    ],
)
def test_a_bad_goal_pose_is_refused_in_one_line(frame, x, why):
    from amr_twin.live.inputs import InputError, decode_goal_pose

    with pytest.raises(InputError, match=re.escape(why)):
        decode_goal_pose(_pose_stamped(frame, x, 0.0, 0.0), "cdr")
