"""A robot's namespace: topics under /<name>/, its frames prefixed, the shared frames kept."""

import pytest

from amr_twin.ros.geometry_messages import TFMessage
from amr_twin.ros.messages import Header, Time
from amr_twin.ros.robot_namespace import RobotNamespace
from amr_twin.ros.ros_state import frame_transform, ground_truth, joint_state


def test_topics_and_frames():
    ns = RobotNamespace("amr-2")
    assert ns.topic("odom") == "/amr-2/odom"
    assert ns.topic("/imu/data_raw") == "/amr-2/imu/data_raw"
    assert [ns.topic(t) for t in ("tf", "/tf_static", "/clock")] == ["/tf", "/tf_static", "/clock"]
    assert ns.frame("base_link") == "amr-2/base_link"
    assert ns.frame("amr-2/base_link") == "amr-2/base_link"
    assert [ns.frame(f) for f in ("map", "world", "uwb_anchor_3", "")] == [
        "map",
        "world",
        "uwb_anchor_3",
        "",
    ]
    with pytest.raises(ValueError, match="name"):
        RobotNamespace("a/b")


def test_messages_copied_with_the_robots_frames():
    ns = RobotNamespace("amr-1")
    tf = TFMessage(
        [
            frame_transform("odom", "base_link", (1, 2, 0), (1, 0, 0, 0)),
            frame_transform("map", "odom", (0, 0, 0), (1, 0, 0, 0)),
        ]
    )
    out = ns.message(tf)
    assert [(t.header.frame_id, t.child_frame_id) for t in out.transforms] == [
        ("amr-1/odom", "amr-1/base_link"),
        ("map", "amr-1/odom"),
    ]
    assert tf.transforms[0].header.frame_id == "odom"  # the bus's message is left alone
    odom = ns.message(ground_truth(5, (1, 2, 0), (1, 0, 0, 0), (0, 0, 0), (0, 0, 0)))
    assert (odom.header.frame_id, odom.child_frame_id) == ("world", "amr-1/base_link")
    js = joint_state(0, ["a"], [0.0], [0.0])
    assert ns.message(js).header.frame_id == ""
    assert ns.message(Header(0, Time(), "laser")).frame_id == "amr-1/laser"
