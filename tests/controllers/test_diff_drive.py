"""cmd_vel to wheel commands, saturation and the clock-driven command timeout."""

import math

import pytest


from amr_twin.ros.bus import Bus
from amr_twin.base.clock import VirtualClock
from amr_twin.ros.geometry_messages import Twist, Vector3
from amr_twin.controllers.diff_drive import DiffDriveNode
from amr_twin.controllers.wheel_command import WheelCommandClient, WheelCommandService
from amr_twin.model.config import load_config

WHEEL = load_config().wheel


def _client(bus):
    """The thesis geometry (the config's: 0.125 m radius, 0.24 m half separation) the figures below
    use."""
    return WheelCommandClient(
        bus, wheel_radius_m=WHEEL.radius_m, half_separation_m=WHEEL.separation_m / 2
    )


@pytest.fixture
def rig():
    clock = VirtualClock()
    bus = Bus(clock)
    WheelCommandService(bus)
    sent = []
    bus.add_tap(
        lambda topic, msg, t_us: (
            sent.append((t_us, list(msg.data))) if topic == "wheel_Command" else None
        )
    )
    node = DiffDriveNode(bus, clock, _client(bus))
    return clock, bus, node, sent


def _twist(v_m_s, w_rad_s):
    return Twist(Vector3(v_m_s, 0.0, 0.0), Vector3(0.0, 0.0, w_rad_s))


def test_straight_twist(rig):
    clock, bus, node, sent = rig
    bus.publish("cmd_vel", _twist(0.5, 0.0))
    assert sent == [(0, [1.0, 38.19718551635742, 1.0, 38.19718551635742])]
    assert node.last_code == 0


def test_turning_twist_rep103(rig):
    clock, bus, node, sent = rig
    bus.publish("cmd_vel", _twist(math.pi / 3, math.pi / 3))  # 60 deg/s, ICC 1 m left
    data = sent[0][1]
    assert (data[0], data[2]) == (1.0, 1.0)
    assert (data[1], data[3]) == pytest.approx((60.80, 99.20), abs=1e-4)
    bus.publish("cmd_vel", _twist(0.0, -1.0))  # spin clockwise in place
    data = sent[1][1]
    assert (data[0], data[2]) == (1.0, -1.0)
    assert data[1] == pytest.approx(0.24 * 60 / (math.pi * 0.25), abs=1e-4)


def test_zero_twist_is_a_stop_and_pivot_brakes_a_wheel(rig):
    clock, bus, node, sent = rig
    bus.publish("cmd_vel", _twist(0.24, 1.0))  # pivot about the left wheel
    assert sent[0][1][:2] == [0.0, 0.0] and sent[0][1][2] == 1.0
    bus.publish("cmd_vel", _twist(0.0, 0.0))
    assert sent[1][1] == [0.0, 0.0, 0.0, 0.0]


def test_timeout_stops_the_wheels_on_the_clock(rig):
    clock, bus, node, sent = rig
    bus.publish("cmd_vel", _twist(0.5, 0.0))
    assert clock.next_event_us() == 500_000  # a clock event, not polling
    clock.run_until(499_999)
    assert len(sent) == 1 and not node.timed_out
    clock.run_until(500_000)
    assert sent[-1] == (500_000, [0.0, 0.0, 0.0, 0.0]) and node.timed_out
    clock.run_until(5_000_000)
    assert len(sent) == 2  # stops once


def test_each_cmd_vel_rearms_the_timeout(rig):
    clock, bus, node, sent = rig
    bus.publish("cmd_vel", _twist(0.5, 0.0))
    clock.run_until(300_000)
    bus.publish("cmd_vel", _twist(0.5, 0.0))  # identical: not re-sent, timer re-armed
    assert len(sent) == 1
    clock.run_until(799_999)
    assert len(sent) == 1
    clock.run_until(800_000)
    assert sent[-1] == (800_000, [0.0, 0.0, 0.0, 0.0])
    clock.run_until(900_000)
    bus.publish("cmd_vel", _twist(0.5, 0.0))  # after a timeout the same command is sent again
    assert sent[-1][1][0] == 1.0 and len(sent) == 3


def test_configurable_timeout_and_resend():
    clock = VirtualClock()
    bus = Bus(clock)
    WheelCommandService(bus)
    sent = []
    bus.subscribe("wheel_Command", sent.append)
    DiffDriveNode(bus, clock, _client(bus), cmd_timeout_s=0.2, resend_identical=True)
    bus.publish("cmd_vel", _twist(0.5, 0.0))
    bus.publish("cmd_vel", _twist(0.5, 0.0))
    assert len(sent) == 2
    clock.run_until(200_000)
    assert list(sent[-1].data) == [0.0, 0.0, 0.0, 0.0]


def test_saturation_keeps_the_curvature(rig):
    clock, bus, node, sent = rig
    bus.publish("cmd_vel", _twist(20.0, 10.0))  # far beyond MAX_RPM
    data = sent[0][1]
    assert max(data[1], data[3]) == pytest.approx(1054.0, abs=1e-3)
    left, right = 20.0 - 10.0 * 0.24, 20.0 + 10.0 * 0.24
    assert data[1] / data[3] == pytest.approx(left / right, rel=1e-6)


def test_without_saturation_the_command_is_refused():
    clock = VirtualClock()
    bus = Bus(clock)
    WheelCommandService(bus)
    node = DiffDriveNode(bus, clock, _client(bus), saturate=False)
    bus.publish("cmd_vel", _twist(20.0, 0.0))
    assert node.last_code == 1


def test_non_finite_twist_is_ignored(rig):
    clock, bus, node, sent = rig
    bus.publish("cmd_vel", _twist(math.nan, 0.0))
    assert sent == [] and clock.next_event_us() > 10**12


def test_no_server_reports_minus_one_and_retries():
    clock = VirtualClock()
    bus = Bus(clock)
    node = DiffDriveNode(bus, clock, _client(bus))
    bus.publish("cmd_vel", _twist(0.5, 0.0))
    assert node.last_code == -1
    WheelCommandService(bus)
    bus.publish("cmd_vel", _twist(0.5, 0.0))
    assert node.last_code == 0


def test_shutdown_cancels_the_timeout(rig):
    clock, bus, node, sent = rig
    bus.publish("cmd_vel", _twist(0.5, 0.0))
    node.shutdown()
    clock.run_until(1_000_000)
    bus.publish("cmd_vel", _twist(0.7, 0.0))
    assert len(sent) == 1
