"""Wheel odometry: exact arcs, motion signs from wheel_Command, signed input, rate, tf,
measurement windows of one revolution, brake ramp, and a published pose that is
integrated forward only (REP-105: continuous) while it makes up the smoothed pose."""

import math

import numpy as np
import pytest


from amr_twin.ros.bus import Bus
from amr_twin.base.clock import VirtualClock
from amr_twin.ros.messages import Float64, Float64MultiArray
from amr_twin.controllers.odometry import WheelOdometry
from amr_twin.model.config import load_config
from amr_twin.estimation.published_pose import CATCHUP_FLOOR_M_S, CATCHUP_FLOOR_RAD_S

WHEEL = load_config().wheel
GEOMETRY = {"wheel_radius_m": WHEEL.radius_m, "wheel_separation_m": WHEEL.separation_m}
RPM_PER_M_S = 60.0 / (math.pi * 2 * WHEEL.radius_m)
CIRCUMFERENCE_M = 2 * math.pi * WHEEL.radius_m
HELD = {
    "sample_gap_s": math.inf
}  # a sample holds until the next (no silence bound): one sample, long arcs
EXACT = {
    "max_wheel_accel_m_s2": math.inf,
    **HELD,
    **GEOMETRY,
}  # speeds in force at once: analytic arcs


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


def _poses(msgs):
    """(n, 7): t_s, x, y, yaw, vx, vy, w of odometry messages."""
    return np.array(
        [
            (
                m.header.stamp.to_sec(),
                m.pose.pose.position.x,
                m.pose.pose.position.y,
                m.pose.pose.orientation.yaw_rad(),
                m.twist.twist.linear.x,
                m.twist.twist.linear.y,
                m.twist.twist.angular.z,
            )
            for m in msgs
        ]
    )


def test_constant_arc_matches_the_analytic_pose(rig):
    clock, bus, odom_msgs = rig
    odo = WheelOdometry(bus, clock, **EXACT)
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
    assert last.twist.twist.linear.y == 0.0
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
    odo = WheelOdometry(bus, clock, publish_rate_hz=7.0, speed_samples="hold", **EXACT)
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
    odo = WheelOdometry(bus, clock, **EXACT)
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
    odo = WheelOdometry(bus, clock, brake_stop_s=0.1, brake_friction_rpm_s=0.0, **EXACT)
    _firmware(bus, 1, RPM_PER_M_S, 1, RPM_PER_M_S)
    clock.run_until(1_000_000)
    bus.publish("wheel_Command", Float64MultiArray(data=[0.0, 0.0, 0.0, 0.0]))
    clock.run_until(1_050_000)
    odo.update()
    assert odo.x_m == pytest.approx(1.0 + 0.05 * 0.75)  # half-way down the linear ramp
    assert odo.body_velocity()[0] == pytest.approx(0.5)
    clock.run_until(3_000_000)  # the firmware published nothing new: the speed is stale
    assert odo.x_m == pytest.approx(1.0 + 0.5 * 0.1)
    assert odo.body_velocity() == (0.0, 0.0)


def test_signed_input(rig):
    clock, bus, _ = rig
    odo = WheelOdometry(bus, clock, signed_input=True, **EXACT)
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
    odo = WheelOdometry(
        bus,
        clock,
        wheel_radius_multiplier=1.1,
        right_radius_multiplier=1.02,
        wheel_separation_multiplier=1.05,
        **EXACT,
    )
    odo.set_wheel_speeds_rpm(RPM_PER_M_S, RPM_PER_M_S)
    v, w = odo.body_velocity()
    assert v == pytest.approx(1.1 * (1 + 1.02) / 2)
    assert w == pytest.approx(1.1 * 0.02 / (0.48 * 1.05))


def test_rate_covariances_and_sequence(rig):
    clock, bus, odom_msgs = rig
    WheelOdometry(
        bus,
        clock,
        **GEOMETRY,
        publish_rate_hz=20.0,
        pose_covariance_diagonal=[1, 2, 3, 4, 5, 6],
        twist_covariance_diagonal=[0.1] * 6,
    )
    clock.run_until(1_000_000)
    assert len(odom_msgs) == 21  # the first at the start: tf covers the sensors' first stamps
    assert [m.header.stamp.to_us() for m in odom_msgs[:3]] == [0, 50_000, 100_000]
    assert [m.header.seq for m in odom_msgs[:3]] == [0, 1, 2]
    cov = odom_msgs[0].pose.covariance.reshape(6, 6)
    assert np.array_equal(np.diag(cov), [1, 2, 3, 4, 5, 6]) and cov[0, 1] == 0
    assert odom_msgs[0].twist.covariance[35] == 0.1
    with pytest.raises(ValueError):
        WheelOdometry(bus, clock, **GEOMETRY, pose_covariance_diagonal=[1, 2])


def test_shutdown_stops_publishing(rig):
    clock, bus, odom_msgs = rig
    odo = WheelOdometry(bus, clock, **GEOMETRY)
    clock.run_until(100_000)
    odo.shutdown()
    clock.run_until(1_000_000)
    assert len(odom_msgs) == 6


def _start_one_revolution_late(rig, command_rpm=60.0, **options):
    """At rest 1 s, commanded to ``command_rpm``; the wheels turn at 60 RPM from 1.5 s, and the
    first sample (mean of that revolution) arrives at 2.5 s."""
    clock, bus, odom_msgs = rig
    odo = WheelOdometry(bus, clock, **GEOMETRY, **{**HELD, **options})
    clock.run_until(1_000_000)
    bus.publish("wheel_Command", Float64MultiArray(data=[1.0, command_rpm, 1.0, command_rpm]))
    clock.run_until(1_500_000)  # the wheels turn from here on (true motion)
    clock.run_until(2_500_000)  # one revolution (1 s at 60 RPM) ended now
    return clock, bus, odom_msgs, odo


def test_a_sample_is_the_mean_over_the_revolution_before_it(rig):
    """Faithful firmware: one sample per revolution, stamped at its end; the smoothed pose has
    it."""
    clock, bus, odom_msgs, odo = _start_one_revolution_late(rig)
    # nothing measured yet: the commanded 60 RPM, reached over the 0.5 s start ramp from 1 s
    assert odo.x_m == pytest.approx(1.25 * CIRCUMFERENCE_M, rel=1e-9)
    bus.publish("wheel0_Vel", Float64(60.0))
    bus.publish("wheel1_Vel", Float64(60.0))
    # the wheels stood until the window 1.5-2.5 s at 60 RPM: one revolution, in hindsight
    assert odo.smoothed_pose()[0] == pytest.approx(CIRCUMFERENCE_M, rel=1e-9)
    assert odo.x_m == pytest.approx(
        1.25 * CIRCUMFERENCE_M, rel=1e-9
    )  # the published pose does not jump
    clock.run_until(3_000_000)
    assert odo.smoothed_pose()[0] == pytest.approx(1.5 * CIRCUMFERENCE_M, rel=1e-9)  # held after it
    assert (
        odo.smoothed_pose()[0] < odo.x_m < 1.75 * CIRCUMFERENCE_M
    )  # slower than the wheels: made up
    clock.run_until(6_000_000)  # made up by then, no overshoot
    assert odo.x_m == pytest.approx(odo.smoothed_pose()[0], abs=1e-3)
    assert odo.x_m == pytest.approx(4.5 * CIRCUMFERENCE_M, abs=1e-3)
    assert odom_msgs[-1].pose.pose.position.x == pytest.approx(odo.x_m)
    hold = WheelOdometry(rig[1], rig[0], **GEOMETRY, speed_samples="hold")
    assert hold.speed_samples == "hold"


def test_published_pose_is_continuous_and_its_twist_integrates_to_it(rig):
    """REP-105: no step larger than the wheels' motion allows (plus the bounded correction),
    and the published twist is the one the pose moves with."""
    clock, bus, odom_msgs, odo = _start_one_revolution_late(
        rig, command_rpm=30.0
    )  # faster than commanded
    bus.publish("wheel0_Vel", Float64(60.0))
    bus.publish("wheel1_Vel", Float64(62.0))  # the right wheel a little faster: a turn to make up
    clock.run_until(7_000_000)
    a = _poses(odom_msgs)
    assert np.all(np.diff(a[:, 0]) == pytest.approx(0.02))
    step_m = np.hypot(np.diff(a[:, 1]), np.diff(a[:, 2]))
    rim_m = 62.0 / RPM_PER_M_S * 0.02  # the faster wheel's travel in one period
    assert step_m.max() <= (1 + odo.catchup_max_fraction) * rim_m + CATCHUP_FLOOR_M_S * 0.02 + 1e-9
    assert (
        np.abs(np.diff(a[:, 3])).max()
        <= (1 + odo.catchup_max_fraction) * 2 * rim_m / 0.48 + CATCHUP_FLOOR_RAD_S * 0.02 + 1e-9
    )
    assert step_m.max() > rim_m  # it did make up something
    # integrate the published twists (held over each period) with the SE(2) exponential
    from amr_twin.estimation.dead_reckoning import twist_step

    pose = tuple(a[0, 1:4])
    for k in range(len(a) - 1):
        pose = twist_step(pose, a[k + 1, 4], a[k + 1, 5], a[k + 1, 6], a[k + 1, 0] - a[k, 0])
    assert pose[:2] == pytest.approx(tuple(a[-1, 1:3]), abs=0.02)
    assert pose[2] == pytest.approx(a[-1, 3], abs=0.002)
    # the smoothed pose jumped at the sample instead
    smoothed = odo.smoothed_pose()
    assert smoothed[2] > 0 and odo.yaw_rad == pytest.approx(smoothed[2], abs=1e-3)


def test_hold_mode_lags_and_never_makes_up(rig):
    clock, bus, _, odo = _start_one_revolution_late(rig, speed_samples="hold")
    assert odo.x_m == 0.0  # no stand-in for a start: at rest until the first sample
    bus.publish("wheel0_Vel", Float64(60.0))
    bus.publish("wheel1_Vel", Float64(60.0))
    clock.run_until(6_000_000)
    assert odo.x_m == pytest.approx(3.5 * CIRCUMFERENCE_M, abs=0.02)  # the first revolution is lost


def test_windows_are_clipped_at_the_previous_sample(rig):
    """Improved firmware: samples faster than a revolution cover the time since the previous."""
    clock, bus, _ = rig
    odo = WheelOdometry(bus, clock, **GEOMETRY)
    bus.publish("wheel_Command", Float64MultiArray(data=[1.0, 30.0, -1.0, 30.0]))
    for k in range(1, 11):
        clock.run_until(k * 100_000)
        bus.publish("wheel0_Vel", Float64(30.0))
        bus.publish("wheel1_Vel", Float64(30.0))
    yaw_rate = 2 * (30 * 2 * math.pi / 60 * 0.125) / 0.48
    assert odo.smoothed_pose()[2] == pytest.approx(-yaw_rate * 1.0, rel=1e-9)
    clock.run_until(2_000_000)
    assert math.remainder(odo.yaw_rad + yaw_rate * 2.0, 2 * math.pi) == pytest.approx(0.0, abs=1e-3)
    with pytest.raises(ValueError):
        WheelOdometry(bus, clock, **GEOMETRY, speed_samples="guess")


def test_a_sample_supersedes_the_assumed_brake_ramp(rig):
    clock, bus, _ = rig
    odo = WheelOdometry(
        bus, clock, brake_stop_s=0.5, brake_friction_rpm_s=0.0, signed_input=False, **EXACT
    )
    _firmware(bus, 1, RPM_PER_M_S, 1, RPM_PER_M_S)
    clock.run_until(1_000_000)
    bus.publish("wheel_Command", Float64MultiArray(data=[0.0, 0.0, 0.0, 0.0]))
    clock.run_until(1_100_000)
    ramp_m = 0.1 * (1.0 + 0.8) / 2  # travelled on the assumed ramp
    assert odo.x_m == pytest.approx(1.0 + ramp_m)
    bus.publish("wheel0_Vel", Float64(0.0))  # measured: stopped since the brake
    bus.publish("wheel1_Vel", Float64(0.0))
    assert odo.smoothed_pose()[0] == pytest.approx(1.0)
    xs = []
    for k in range(
        1, 101
    ):  # standing wheels: the published pose settles at the floor rate, no jump
        clock.run_until(1_100_000 + 20_000 * k)
        xs.append(odo.x_m)
    assert np.all(np.diff(xs) <= 0) and -np.diff(xs).max() <= CATCHUP_FLOOR_M_S * 0.02 + 1e-12
    assert xs[0] > 1.0 + ramp_m - 0.002 and xs[-1] == pytest.approx(1.0, abs=1e-3)


def test_bad_options_are_refused(rig):
    clock, bus, _ = rig
    for bad in (
        {"catchup_time_s": 0.0},
        {"catchup_max_fraction": -0.1},
        {"max_wheel_accel_m_s2": 0.0},
        {"publish_rate_hz": 0.0},
    ):
        with pytest.raises(ValueError, match=next(iter(bad))):
            WheelOdometry(bus, clock, **GEOMETRY, **bad)


def test_a_wheel_that_stops_without_a_brake_reads_at_rest_after_the_silence_bound(rig):
    """Thesis firmware: nothing is published once a wheel stands. Silent past its next sample,
    the wheel's speed falls under 60 / (time since the sample - gaps) RPM, and it is at rest
    once that bound falls below rest_rpm."""
    clock, bus, _ = rig
    odo = WheelOdometry(
        bus, clock, max_wheel_accel_m_s2=math.inf, sample_gap_s=0.4, rest_rpm=10.0, **GEOMETRY
    )
    bus.publish("wheel_Command", Float64MultiArray(data=[1.0, 60.0, 1.0, 60.0]))
    for t_us in (
        1_000_000,
        2_400_000,
        3_800_000,
    ):  # a revolution at 60 RPM, then the firmware's gap
        clock.run_until(t_us)
        bus.publish("wheel0_Vel", Float64(60.0))
        bus.publish("wheel1_Vel", Float64(60.0))
    x_sample = odo.smoothed_pose()[0]
    clock.run_until(5_100_000)  # the next sample is not due yet: the speed holds
    assert odo.body_velocity()[0] == pytest.approx(60.0 / RPM_PER_M_S)
    clock.run_until(7_000_000)  # overdue: under the bound 60 / (7.0 - 3.8 - 0.4) RPM
    assert (
        0.0 < odo.body_velocity()[0] <= 1.03 * 60.0 / 2.8 / RPM_PER_M_S
    )  # knots 1.25x apart in time
    clock.run_until(10_300_000)  # 60 / (10.3 - 4.2) < 10 RPM: at rest
    assert odo.body_velocity() == (0.0, 0.0)
    x_rest = odo.smoothed_pose()[0]
    clock.run_until(30_000_000)
    assert odo.smoothed_pose()[0] == x_rest and odo.x_m == pytest.approx(x_rest, abs=1e-3)
    # held a revolution and the gap (1.4 rev), then at most ln(6) rev under the bound
    assert x_rest - x_sample <= (1.4 + 1.03 * math.log(6.0)) * CIRCUMFERENCE_M
    assert (odo.yaw_rad, odo.y_m) == pytest.approx((0.0, 0.0), abs=1e-9)


def _stop_and_restart(bus, clock, gaps_s=(0.25, 0.4), until_s=17.0):
    """Both wheels alike, straight: 60 RPM, brake at 5 s (to rest by 5.5 s), start at 10 s (60 RPM
    by 10.5 s). Each wheel publishes one revolution, then counts the next after its gap (as the
    thesis firmware does): the revolution across the stop is published after the restart.
    Returns the true distance, m."""

    def rpm(t):
        if t < 5.0:
            return 60.0
        if t < 10.0:
            return 60.0 * max(0.0, 1.0 - (t - 5.0) / 0.5)
        return 60.0 * min(1.0, (t - 10.0) / 0.5)

    dt = 0.001
    revs, count_from = 0.0, [(0.0, None), (0.0, None)]  # (count start, revs at it)
    commands = {
        0: [1.0, 60.0, 1.0, 60.0],
        5000: [0.0, 0.0, 0.0, 0.0],
        10000: [1.0, 60.0, 1.0, 60.0],
    }
    for k in range(int(until_s / dt)):
        t = k * dt
        clock.run_until(int(round(t * 1e6)))
        if k in commands:
            bus.publish("wheel_Command", Float64MultiArray(data=commands[k]))
        for wheel in (0, 1):
            start, at = count_from[wheel]
            if at is None and t >= start:
                count_from[wheel] = (t, revs)
            elif at is not None and revs - at >= 1.0:
                bus.publish(f"wheel{wheel}_Vel", Float64(60.0 / (t - start)))
                count_from[wheel] = (t + gaps_s[wheel], None)
        revs += 0.5 * (rpm(t) + rpm(t + dt)) / 60.0 * dt
    return revs * CIRCUMFERENCE_M


def test_a_restart_does_not_turn_when_the_wheels_do_not(rig):
    """The revolutions across a stop are published after the restart, one wheel long after the
    other: each keeps its count, and a wheel not measured since the start moves as the other."""
    clock, bus, odom_msgs = rig
    odo = WheelOdometry(bus, clock, **GEOMETRY)
    distance_m = _stop_and_restart(bus, clock)
    a = _poses(odom_msgs)
    assert np.degrees(np.abs(a[:, 3]).max()) < 5.0  # published: never more than 5 degrees off
    assert (
        abs(math.degrees(odo.smoothed_pose()[2])) < 4.0
    )  # the rest: a sample during the brake ramp
    assert odo.smoothed_pose()[0] == pytest.approx(distance_m, rel=0.03)
    assert odo.x_m == pytest.approx(distance_m, rel=0.03)
    standing = (a[:, 0] > 6.0) & (a[:, 0] < 10.0)
    assert np.ptp(a[standing, 1]) < 0.02  # still while the wheels stand
