"""What the bridge takes from the graph is checked as a live client's input; what it gives keeps the
fields."""

import math
from types import SimpleNamespace

import pytest

from conftest import needs_ros1
from amr_twin.ros1.messages import InputError, twist_from_ros, wheel_command_from_ros


def _vec(x=0.0, y=0.0, z=0.0):
    return SimpleNamespace(x=x, y=y, z=z)


def test_a_wheel_command_from_the_graph_is_checked_as_a_request():
    cmd = wheel_command_from_ros(SimpleNamespace(data=[1.0, 53.476, -1.0, 20.0]))
    assert cmd.data == [1.0, 53.476, -1.0, 20.0]
    for bad, field in (
        ([2.0, 10.0, 1.0, 10.0], "motionL"),
        ([1.0, 2000.0, 1.0, 10.0], "speedL"),
        ([1.0, 10.0, 1.0, math.nan], "speedR"),
        ([1.0, 10.0, 1.0], "3 values"),
    ):
        with pytest.raises(InputError, match=field):
            wheel_command_from_ros(SimpleNamespace(data=bad))


def test_a_twist_from_the_graph_must_be_finite():
    t = twist_from_ros(SimpleNamespace(linear=_vec(0.3), angular=_vec(z=-0.5)))
    assert (t.linear.x, t.angular.z) == (0.3, -0.5)
    with pytest.raises(InputError, match="angular.z"):
        twist_from_ros(SimpleNamespace(linear=_vec(0.3), angular=_vec(z=math.inf)))


@needs_ros1
def test_the_generic_converter_fills_rospys_class_field_by_field():
    from amr_twin.ros import ros_state
    from amr_twin.ros1.messages import Ros1Messages

    conv = Ros1Messages()
    odom = conv.to_ros(
        ros_state.ground_truth(
            1_500_000, [1.0, 2.0, 0.1], [1.0, 0.0, 0.0, 0.0], [0.4, 0.0, 0.0], [0.0, 0.0, 0.2]
        )
    )
    assert odom._type == "nav_msgs/Odometry" and odom.header.frame_id == "world"
    assert (odom.header.stamp.secs, odom.header.stamp.nsecs) == (1, 500_000_000)
    assert odom.pose.pose.position.y == 2.0 and odom.twist.twist.angular.z == 0.2
    assert isinstance(odom.pose.covariance, list) and len(odom.pose.covariance) == 36
