"""The robot's geometry is read from the parameter file by every consumer.

A robot with other wheels (radius 0.15 m instead of 0.125 m), a wider track (0.56 m instead
of 0.48 m) and motors of 20 pole pairs (120 SC changes per revolution instead of 90) is
driven: the firmware's published speeds, the cmd_vel conversion and the wheel odometry must
all follow the file. A constant planted back anywhere on the path (a radius of 0.125 m in the
client or the odometry, 90 edges in a firmware, 0.48 m in the odometry) puts the odometry's
distance or turn off by 15 to 33 %, well outside the few per cent of tyre slip allowed here.
"""

import math

import numpy as np
import pytest

from amr_twin.estimation.ekf import EkfNode
from amr_twin.model.config import load_config
from amr_twin.assembly.twin import TwinOptions
from amr_twin.assembly.command import Command
from amr_twin.recording.run import run_command

OTHER = {"wheel.radius_m": 0.15, "wheel.separation_m": 0.56, "wheel.hall_pole_pairs": 20}


@pytest.fixture(scope="module")
def other():
    return load_config(overrides=OTHER)


def test_a_straight_run_is_measured_with_the_configured_wheels(other):
    """0.5 m/s for 4 s: the wheels turn at the configured radius's RPM and the odometry's
    distance is the true distance (both taken from 1.5 s on, after the first samples)."""
    result = run_command(
        other,
        Command("linear", speed_m_s=0.5),
        4.0,
        TwinOptions(world="empty", visuals=False, firmware="improved"),
    )
    s = result.series
    rpm_true = s.true_rpm[s.t_s > 2.5].mean(axis=0)
    assert rpm_true == pytest.approx(
        [0.5 * 60 / (2 * math.pi * 0.15)] * 2, rel=0.03
    )  # the client's radius
    published = np.array([s.published[w][s.published[w][:, 0] > 2.5, 1].mean() for w in (0, 1)])
    assert published == pytest.approx(
        rpm_true, rel=0.03
    )  # the firmware counts 120 edges a revolution
    t0, t1 = 1.5, s.odom[-1, 0]
    odom = [np.interp(t, s.odom[:, 0], s.odom[:, 1]) for t in (t0, t1)]
    true = [np.interp(t, s.t_s, s.pose[:, 0]) - s.pose[0, 0] for t in (t0, t1)]
    assert odom[1] - odom[0] == pytest.approx(true[1] - true[0], rel=0.04)


def test_the_thesis_firmware_counts_the_configured_edges(other):
    """The faithful firmware samples once a revolution of SC changes: at 0.5 m/s (32 RPM) its
    samples after the first revolution say the true speed of that revolution."""
    result = run_command(
        other,
        Command("linear", speed_m_s=0.5),
        8.0,
        TwinOptions(world="empty", visuals=False, firmware="faithful"),
    )
    s = result.series
    for w in (0, 1):
        samples = s.published[w][s.published[w][:, 0] > 4.0]
        assert len(samples) >= 2
        true = s.true_rpm[
            (s.t_s > samples[0, 0] - 60 / samples[0, 1]) & (s.t_s <= samples[-1, 0]), w
        ].mean()
        assert samples[:, 1].mean() == pytest.approx(true, rel=0.04)


def test_a_turn_on_the_spot_is_measured_with_the_configured_track(other):
    """30 deg/s about the centre for 4 s: the odometry's yaw follows the true yaw."""
    result = run_command(
        other,
        Command("angular", speed_deg_s=30.0, icc_m=0.0),
        4.0,
        TwinOptions(world="empty", visuals=False, firmware="improved"),
    )
    s = result.series
    true_yaw = np.unwrap(s.pose[:, 2])
    t0, t1 = 1.5, s.odom[-1, 0]
    odom = [np.interp(t, s.odom[:, 0], np.unwrap(s.odom[:, 3])) for t in (t0, t1)]
    true = [np.interp(t, s.t_s, true_yaw) for t in (t0, t1)]
    assert math.degrees(true[1] - true[0]) == pytest.approx(
        30.0 * (t1 - t0), rel=0.08
    )  # the client's track
    assert odom[1] - odom[0] == pytest.approx(true[1] - true[0], rel=0.05)


def test_the_ekf_rest_check_uses_the_configured_track(other):
    """A yaw rate whose rim speed is at rest on the thesis' 0.24 m half track but not on 0.28 m."""
    thesis = load_config()
    w = 0.5 * (thesis.ekf.rest_speed_m_s / 0.24 + thesis.ekf.rest_speed_m_s / 0.28)
    at_rest = {}
    for name, cfg in (("thesis", thesis), ("other", other)):
        node = EkfNode(
            cfg.ekf, wheel_separation_m=cfg.wheel.separation_m, use_imu=True, use_uwb=False
        )
        at_rest[name] = node.gyro_rest.at_rest((0.0, w))
    assert at_rest == {"thesis": True, "other": False}
