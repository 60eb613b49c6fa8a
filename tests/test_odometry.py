"""Wheel odometry: exact arcs, motion signs from wheel_Command, signed input, rate, tf,
measurement windows of one revolution, brake ramp."""

import math

import numpy as np
import pytest


from amr_twin.bus import Bus
from amr_twin.clock import VirtualClock
from amr_twin.messages import Float64, Float64MultiArray
from amr_twin.controllers.odometry import WheelOdometry

RPM_PER_M_S = 60.0 / (math.pi * 0.25)


@pytest.fixture
def rig():
    clock = VirtualClock()
    bus = Bus(clock)
    odom_msgs = []
    bus.subscribe("odom", odom_msgs.append)
    return clock, bus, odom_msgs


def _firmware(bus, motion_l, rpm_l, motion_r, rpm_r):
    """What the PC sees: the command, then the SC speed magnitudes."""
    bus.publish("wheel_Command", Float64MultiArray(data=[motion_l, rpm_l, motion_r, rpm_r]))
    bus.publish("wheel0_Vel", Float64(rpm_l))
    bus.publish("wheel1_Vel", Float64(rpm_r))


def test_constant_arc_matches_the_analytic_pose(rig):
    clock, bus, odom_msgs = rig
    odo = WheelOdometry(bus, clock)
    _firmware(bus, 1, 60.8, 1, 99.2)  # 60 deg/s about an ICC 1 m to the left
    clock.run_until(2_000_000)
    w = math.pi / 3
    last = odom_msgs[-1]
    assert last.header.stamp.to_us() == 2_000_000
    assert last.header.frame_id == "odom" and last.child_frame_id == "base_link"
    pose = last.pose.pose
    assert pose.position.x == pytest.approx(math.sin(2 * w), abs=1e-9)
    assert pose.position.y == pytest.approx(1 - math.cos(2 * w), abs=1e-9)
    assert pose.orientation.yaw_rad() == pytest.approx(2 * w, abs=1e-9)
    assert last.twist.twist.linear.x == pytest.approx(w)
    assert last.twist.twist.angular.z == pytest.approx(w)
    tf = bus.tf.lookup_transform("odom", "base_link")
    assert (tf.translation.x, tf.translation.y) == pytest.approx((odo.x_m, odo.y_m))
    clock.run_until(4_000_000)  # past half a turn: yaw wraps into (-pi, pi]
    assert odo.yaw_rad == pytest.approx(4 * w - 2 * math.pi, abs=1e-9)
    assert (odo.x_m, odo.y_m) == pytest.approx((math.sin(4 * w), 1 - math.cos(4 * w)), abs=1e-9)
    clock.run_until(6_000_000)  # a whole circle
    assert (odo.x_m, odo.y_m) == pytest.approx((0.0, 0.0), abs=1e-9)


def test_arc_with_speed_changes_between_publications(rig):
    clock, bus, _ = rig
    odo = WheelOdometry(bus, clock, publish_rate_hz=7.0, speed_samples="hold")
    _firmware(bus, 1, 60.8, 1, 99.2)
    clock.run_until(370_123)  # not a publication instant
    _firmware(bus, 1, 0.5 * RPM_PER_M_S, 1, 0.5 * RPM_PER_M_S)  # then straight at 0.5 m/s
    clock.run_until(1_000_000)
    odo.update()
    yaw = math.pi / 3 * 0.370123
    x = math.sin(yaw) + 0.5 * 0.629877 * math.cos(yaw)
    y = 1 - math.cos(yaw) + 0.5 * 0.629877 * math.sin(yaw)
    assert (odo.x_m, odo.y_m, odo.yaw_rad) == pytest.approx((x, y, yaw), abs=1e-9)


def test_clockwise_about_icc_right_and_backward(rig):
    clock, bus, _ = rig
    odo = WheelOdometry(bus, clock)
    _firmware(bus, 1, 99.2, 1, 60.8)  # ch. 5: clockwise, ICC 1 m right
    clock.run_until(1_000_000)
    w = -math.pi / 3
    assert (odo.x_m, odo.y_m) == pytest.approx((-math.sin(w), -(1 - math.cos(w))), abs=1e-9)
    odo.reset()
    _firmware(bus, -1, 1.2 * RPM_PER_M_S, -1, 1.2 * RPM_PER_M_S)  # backward 1.2 m/s
    clock.run_until(2_000_000)
    assert (odo.x_m, odo.y_m, odo.yaw_rad) == pytest.approx((-1.2, 0.0, 0.0), abs=1e-9)


def test_brake_command_zeroes_a_stale_speed_after_the_brake_ramp(rig):
    clock, bus, _ = rig
    odo = WheelOdometry(bus, clock, brake_stop_s=0.1)
    _firmware(bus, 1, RPM_PER_M_S, 1, RPM_PER_M_S)
    clock.run_until(1_000_000)
    bus.publish("wheel_Command", Float64MultiArray(data=[0.0, 0.0, 0.0, 0.0]))
    clock.run_until(1_050_000)
    odo.update()
    assert odo.x_m == pytest.approx(1.0 + 0.05 * 0.75)  # half-way down the linear ramp
    assert odo.body_velocity()[0] == pytest.approx(0.5)
    clock.run_until(3_000_000)  # the firmware published nothing new: the speed is stale
    assert odo.x_m == pytest.approx(1.0 + 0.5 * 0.1)


def test_signed_input(rig):
    clock, bus, _ = rig
    odo = WheelOdometry(bus, clock, signed_input=True)
    bus.publish("wheel_Command", Float64MultiArray(data=[1.0, 50.0, 1.0, 50.0]))  # ignored
    bus.publish("wheel0_Vel", Float64(-RPM_PER_M_S))
    bus.publish("wheel1_Vel", Float64(RPM_PER_M_S))
    clock.run_until(500_000)
    assert odo.yaw_rad == pytest.approx(2.0 / 0.48 * 0.5)
    assert (odo.x_m, odo.y_m) == pytest.approx((0.0, 0.0), abs=1e-12)
    odo.set_wheel_speeds_rpm(RPM_PER_M_S, RPM_PER_M_S)
    assert odo.body_velocity() == pytest.approx((1.0, 0.0))


def test_calibration_multipliers(rig):
    clock, bus, _ = rig
    odo = WheelOdometry(bus, clock, wheel_radius_multiplier=1.1, right_radius_multiplier=1.02,
                        wheel_separation_multiplier=1.05)
    odo.set_wheel_speeds_rpm(RPM_PER_M_S, RPM_PER_M_S)
    v, w = odo.body_velocity()
    assert v == pytest.approx(1.1 * (1 + 1.02) / 2)
    assert w == pytest.approx(1.1 * 0.02 / (0.48 * 1.05))


def test_rate_covariances_and_sequence(rig):
    clock, bus, odom_msgs = rig
    WheelOdometry(bus, clock, publish_rate_hz=20.0, pose_covariance_diagonal=[1, 2, 3, 4, 5, 6],
                  twist_covariance_diagonal=[0.1] * 6)
    clock.run_until(1_000_000)
    assert len(odom_msgs) == 20
    assert [m.header.stamp.to_us() for m in odom_msgs[:3]] == [50_000, 100_000, 150_000]
    assert [m.header.seq for m in odom_msgs[:3]] == [0, 1, 2]
    cov = odom_msgs[0].pose.covariance.reshape(6, 6)
    assert np.array_equal(np.diag(cov), [1, 2, 3, 4, 5, 6]) and cov[0, 1] == 0
    assert odom_msgs[0].twist.covariance[35] == 0.1
    with pytest.raises(ValueError):
        WheelOdometry(bus, clock, pose_covariance_diagonal=[1, 2])


def test_shutdown_stops_publishing(rig):
    clock, bus, odom_msgs = rig
    odo = WheelOdometry(bus, clock)
    clock.run_until(100_000)
    odo.shutdown()
    clock.run_until(1_000_000)
    assert len(odom_msgs) == 5


def test_a_sample_is_the_mean_over_the_revolution_before_it(rig):
    """Faithful firmware: one sample per revolution, stamped at its end."""
    clock, bus, odom_msgs = rig
    odo = WheelOdometry(bus, clock)
    clock.run_until(1_000_000)  # at rest
    bus.publish("wheel_Command", Float64MultiArray(data=[1.0, 60.0, 1.0, 60.0]))
    clock.run_until(1_200_000)
    assert odo.x_m == 0.0  # nothing measured yet
    clock.run_until(2_500_000)  # one revolution (1 s at 60 RPM) ended now
    bus.publish("wheel0_Vel", Float64(60.0))
    bus.publish("wheel1_Vel", Float64(60.0))
    circumference_m = 2 * math.pi * 0.125
    # gap 1.0-1.5 s interpolated 0 -> 60 RPM, then the window 1.5-2.5 s at 60 RPM
    assert odo.x_m == pytest.approx(1.25 * circumference_m, rel=1e-9)
    clock.run_until(3_000_000)  # held after the newest window
    assert odo.x_m == pytest.approx(1.75 * circumference_m, rel=1e-9)
    assert odom_msgs[-1].pose.pose.position.x == pytest.approx(odo.x_m)
    hold = WheelOdometry(bus, clock, speed_samples="hold")
    assert hold.speed_samples == "hold"


def test_windows_are_clipped_at_the_previous_sample(rig):
    """Improved firmware: samples faster than a revolution cover the time since the previous."""
    clock, bus, _ = rig
    odo = WheelOdometry(bus, clock)
    bus.publish("wheel_Command", Float64MultiArray(data=[1.0, 30.0, -1.0, 30.0]))
    for k in range(1, 11):
        clock.run_until(k * 100_000)
        bus.publish("wheel0_Vel", Float64(30.0))
        bus.publish("wheel1_Vel", Float64(30.0))
    yaw_rate = 2 * (30 * 2 * math.pi / 60 * 0.125) / 0.48
    assert odo.yaw_rad == pytest.approx(-yaw_rate * 1.0, rel=1e-9)
    with pytest.raises(ValueError):
        WheelOdometry(bus, clock, speed_samples="guess")


def test_a_sample_supersedes_the_assumed_brake_ramp(rig):
    clock, bus, _ = rig
    odo = WheelOdometry(bus, clock, brake_stop_s=0.5, signed_input=False)
    _firmware(bus, 1, RPM_PER_M_S, 1, RPM_PER_M_S)
    clock.run_until(1_000_000)
    bus.publish("wheel_Command", Float64MultiArray(data=[0.0, 0.0, 0.0, 0.0]))
    clock.run_until(1_100_000)
    bus.publish("wheel0_Vel", Float64(0.0))  # measured: stopped since the brake
    bus.publish("wheel1_Vel", Float64(0.0))
    clock.run_until(2_000_000)
    assert odo.x_m == pytest.approx(1.0)
