"""ROS 1 serialised sizes, type names and stamp helpers of amr_twin.ros.messages and its
geometry_msgs/tf2_msgs/nav_msgs (geometry_messages) and sensor_msgs (sensor_messages) families."""

import math

import numpy as np
import pytest


from amr_twin.ros import geometry_messages as g, messages as m, sensor_messages as s


def test_type_names_are_ros_names():
    assert s.LaserScan._type == "sensor_msgs/LaserScan"
    assert g.Odometry._type == "nav_msgs/Odometry"
    assert g.TFMessage._type == "tf2_msgs/TFMessage"
    assert m.Float64MultiArray._type == "std_msgs/Float64MultiArray"
    assert s.Imu()._type == "sensor_msgs/Imu"


def test_fixed_sizes():
    assert m.Float64().serialized_size() == 8
    for cls, size in [
        (g.Vector3, 24),
        (g.Point, 24),
        (g.Quaternion, 32),
        (g.Pose, 56),
        (g.Twist, 48),
        (g.Transform, 56),
        (g.PoseWithCovariance, 344),
        (g.TwistWithCovariance, 336),
    ]:
        assert cls().serialized_size() == size, cls


def test_header_and_string_sizes():
    # seq uint32 + stamp 2 x uint32 + uint32 length + bytes
    assert m.Header().serialized_size() == 16
    assert m.Header(frame_id="odom").serialized_size() == 20
    assert m.Header(frame_id="é").serialized_size() == 18  # UTF-8 bytes, not characters


def test_wheel_command_array_size():
    # fig. 3.3: layout with dim [] and data_offset 0, then 4 float64
    msg = m.Float64MultiArray(data=[1.0, 38.2, 1.0, 38.2])
    assert msg.serialized_size() == 4 + 4 + 4 + 4 * 8
    dims = m.MultiArrayLayout(dim=[m.MultiArrayDimension("x", 4, 4)])
    assert m.Float64MultiArray(dims, [0.0] * 4).serialized_size() == (4 + 4 + 1 + 8 + 4) + 4 + 32


def test_variable_message_sizes():
    odom = g.Odometry(header=m.Header(frame_id="odom"), child_frame_id="base_link")
    assert odom.serialized_size() == 20 + 13 + 344 + 336
    imu = s.Imu(header=m.Header(frame_id="imu_link"))
    assert imu.serialized_size() == 24 + 32 + 72 + 24 + 72 + 24 + 72
    mag = s.MagneticField(header=m.Header(frame_id="imu_link"))
    assert mag.serialized_size() == 24 + 24 + 72
    scan = s.LaserScan(
        header=m.Header(frame_id="laser"),
        ranges=np.ones(360, np.float32),
        intensities=np.ones(360, np.float32),
    )
    assert scan.serialized_size() == 21 + 7 * 4 + 4 + 360 * 4 + 4 + 360 * 4
    ts = g.TransformStamped(m.Header(frame_id="odom"), "base_link")
    assert ts.serialized_size() == 20 + 13 + 56
    assert g.TFMessage([ts, ts]).serialized_size() == 4 + 2 * 89


def test_covariance_defaults_are_independent_arrays():
    a, b = g.PoseWithCovariance(), g.PoseWithCovariance()
    a.covariance[0] = 1.0
    assert b.covariance[0] == 0.0 and a.covariance.shape == (36,)
    imu = s.Imu()
    assert imu.orientation_covariance.shape == (9,)


def test_messages_use_slots():
    with pytest.raises(AttributeError):
        g.Twist().linar = 1.0  # typo must not create a field


def test_time_from_microseconds_is_exact():
    t = m.Time.from_us(12_345_678_901)
    assert (t.sec, t.nanosec) == (12_345, 678_901_000)
    assert t.to_us() == 12_345_678_901
    assert m.Time.from_sec(1.5) == m.Time(1, 500_000_000)
    assert m.Time.from_us(1_500_000).to_sec() == pytest.approx(1.5)


@pytest.mark.parametrize("yaw", [0.0, 0.3, -2.0, math.pi - 1e-9])
def test_quaternion_yaw_round_trip(yaw):
    q = g.Quaternion.from_yaw(yaw)
    assert q.yaw_rad() == pytest.approx(yaw)
    assert q.x**2 + q.y**2 + q.z**2 + q.w**2 == pytest.approx(1.0)
