"""The thesis' printed command conversions (figs. 3.3-3.7, ch. 5) and return codes (§4.2.1)."""

import logging
import math

import pytest


from amr_twin.ros.bus import Bus
from amr_twin.base.clock import VirtualClock
from amr_twin.controllers.wheel_command import (
    MAX_RPM,
    MIN_RPM,
    WheelCommandClient,
    WheelCommandRequest,
    WheelCommandService,
    wheel_Command_Client,
    wheel_Command_Service,
)
from amr_twin.model.config import load_config

WHEEL = load_config().wheel
GEOMETRY = {"wheel_radius_m": WHEEL.radius_m, "half_separation_m": WHEEL.separation_m / 2}
"""The configured geometry: the thesis' (0.125 m, 0.48 m), with which its printed figures were
computed."""


@pytest.fixture
def node():
    """A bus with the service running; returns (client, list of published data)."""
    bus = Bus(VirtualClock())
    WheelCommandService(bus)
    published = []
    bus.subscribe("wheel_Command", lambda msg: published.append(list(msg.data)))
    return WheelCommandClient(bus, **GEOMETRY), published


def _check(data, motion_l, speed_l, motion_r, speed_r, abs_tol=5e-3):
    assert data[0] == motion_l and data[2] == motion_r
    assert data[1] == pytest.approx(speed_l, abs=abs_tol)
    assert data[3] == pytest.approx(speed_r, abs=abs_tol)


def test_fig_3_3_linear_half_metre_per_second(node):
    client, published = node
    assert client.linear(0.5) == 0
    # the float32 request field gives exactly the value rostopic echo printed
    assert published == [[1.0, 38.19718551635742, 1.0, 38.19718551635742]]


def test_ch5_linear_forward_0_7(node):
    client, published = node
    assert client.linear(0.7) == 0
    _check(published[0], 1, 53.476, 1, 53.476)
    assert math.floor(published[0][1] * 100) / 100 == 53.47


def test_ch5_linear_backward_1_2(node):
    client, published = node
    assert client.linear(-1.2) == 0
    _check(published[0], -1, 91.673, -1, 91.673)


def test_fig_3_4_linear_backward_0_6(node):
    client, published = node
    assert client.linear(-0.6) == 0
    _check(published[0], -1, 45.8366, -1, 45.8366, abs_tol=1e-4)


def test_fig_3_6_single_motor_left_1_m_s(node):
    client, published = node
    assert client.motor("left", "forward", 1.0) == 0
    assert published == [[1.0, 76.39437103271484, 1.0, 0.0]]  # right wheel free-spins
    assert client.motor(1, "backward", 1.0) == 0
    _check(published[1], 1, 0.0, -1, 76.394)


def test_ch5_rotation_icc_1_m_right_clockwise(node):
    client, published = node
    assert client.angular(-60.0, -1.0) == 0  # REP-103: clockwise is a negative yaw rate
    _check(published[0], 1, 99.20, 1, 60.80)


def test_ch5_rotation_icc_1_m_left_anticlockwise(node):
    client, published = node
    assert client.angular(60.0, 1.0) == 0
    _check(published[0], 1, 60.80, 1, 99.20)


def test_rotation_icc_right_with_positive_rate_reverses_in_rep103_mode(node):
    client, published = node
    assert client.angular(60.0, -1.0) == 0  # same RPMs, robot drives the arc backward
    _check(published[0], -1, 99.20, -1, 60.80)


def test_listing_mode_forces_forward_outside_the_wheels():
    bus = Bus(VirtualClock())
    WheelCommandService(bus)
    published = []
    bus.subscribe("wheel_Command", lambda msg: published.append(list(msg.data)))
    client = WheelCommandClient(bus, **GEOMETRY, listing_motion_codes=True)
    assert client.angular(60.0, -1.0) == 0  # as typed in the thesis' menu
    _check(published[0], 1, 99.20, 1, 60.80)
    assert client.angular(60.0, 0.0) == 0  # |icc| < R: per-wheel sign even in listing mode
    _check(published[1], -1, 19.2, 1, 19.2)


def test_fig_3_5_anticlockwise_40_deg_s_icc_1_m_left(node):
    client, published = node
    assert client.angular(40.0, 1.0) == 0
    # left = 40 pi/180 (1 - 0.24) 60 / (0.25 pi), right with (1 + 0.24)
    _check(published[0], 1, 40.5333, 1, 66.1333, abs_tol=1e-4)


def test_rotation_in_place_and_about_a_wheel(node):
    client, published = node
    assert client.angular(60.0, 0.0) == 0
    _check(published[0], -1, 19.2, 1, 19.2)
    assert client.angular(30.0, 0.24) == 0  # ICC on the left wheel: it free-spins
    _check(published[1], 1, 0.0, 1, 19.2)  # 30 deg/s x 0.48 m


def test_fig_3_7_stop(node):
    client, published = node
    assert client.stop() == 0
    assert published == [[0.0, 0.0, 0.0, 0.0]]


def test_out_of_range_is_a_value_error(node, caplog):
    client, published = node
    with caplog.at_level(logging.ERROR):
        assert client.linear(15.0) == 1  # 1146 RPM > MAX_RPM
    assert client.last_error.startswith("ERROR: linear velocity not valid")
    assert "linear velocity not valid" in caplog.text
    assert client.angular(1000.0, 5.0) == 1
    assert client.last_error.startswith("ERROR: angular velocity not valid")
    assert client.motor("left", "forward", 20.0) == 1
    assert published == []


@pytest.mark.parametrize(
    "call",
    [
        lambda c: c.linear(math.nan),
        lambda c: c.linear(math.inf),
        lambda c: c.angular(math.nan, 1.0),
        lambda c: c.angular(60.0, -math.inf),
        lambda c: c.motor("left", "forward", math.nan),
        lambda c: c.wheels(0.1, math.nan),
    ],
)
def test_non_finite_values_are_refused(node, call):
    client, published = node
    assert call(client) == 1
    assert "not a finite number" in client.last_error
    assert published == []


def test_bad_motor_arguments(node):
    client, _ = node
    assert client.motor("middle", "forward", 1.0) == 1
    assert client.motor("left", "sideways", 1.0) == 1
    assert client.motor("left", "forward", -1.0) == 1


def test_no_server_is_code_minus_one():
    client = WheelCommandClient(Bus(VirtualClock()), **GEOMETRY)
    assert client.linear(0.5) == -1
    assert client.last_error.startswith("ERROR while linear motion")
    assert client.angular(60.0, 1.0) == -1
    assert client.stop() == -1
    assert client.last_error.startswith("ERROR while stop motion")
    assert client.motor("left", "forward", 1.0) == -1
    assert client.wheels(0.1, 0.2) == -1


def test_check_speed_range():
    client = WheelCommandClient(Bus(VirtualClock()), **GEOMETRY)
    assert (MIN_RPM, MAX_RPM) == (0.0, 1054.0)
    assert client.checkSpeed(0.0) and client.checkSpeed(1054.0) and client.checkSpeed(-91.67)
    assert not client.check_speed(1054.1) and not client.check_speed(math.nan)


def test_constants_are_constructor_arguments():
    bus = Bus(VirtualClock())
    WheelCommandService(bus)
    published = []
    bus.subscribe("wheel_Command", lambda msg: published.append(list(msg.data)))
    client = WheelCommandClient(
        bus, wheel_radius_m=0.1, half_separation_m=0.3, max_rpm=50.0, float32_request=False
    )
    assert client.linear(0.5) == 0
    assert published[0][1] == pytest.approx(0.5 * 60 / (math.pi * 0.2), rel=1e-12)
    assert client.angular(60.0, 1.0) == 1  # 1.3 * pi/3 m/s -> 65 RPM > 50
    assert client.linear(-0.5) == 0


def test_wheels_per_wheel_signs_and_brake(node):
    client, published = node
    assert client.wheels(-0.5, 0.0) == 0
    _check(published[0], -1, 38.197, 0, 0.0)
    assert client.wheels(0.0, 0.5, brake_zero=False) == 0
    _check(published[1], 1, 0.0, 1, 38.197)


def test_service_request_is_forwarded_as_published(node):
    client, published = node
    client.bus.call_service("wheel_Command_Service", WheelCommandRequest(-1, 10.5, 1, 0.0))
    assert published == [[-1.0, 10.5, 1.0, 0.0]]
    assert wheel_Command_Client is WheelCommandClient
    assert wheel_Command_Service is WheelCommandService
