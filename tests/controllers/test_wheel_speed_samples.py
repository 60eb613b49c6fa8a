"""Wheel speed estimates from samples and commands (controllers/wheel_speed_samples.py): the
stand-in of a start, its bound, the silence bound's knots as assumptions, revolutions across a stop,
brake ramps."""

import math

import pytest

from amr_twin.estimation.published_pose import PublishedPose
from amr_twin.controllers.wheel_speed_samples import WheelSpeedSamples

S = 1_000_000  # us per s


def _samples(**options):
    """A WheelSpeedSamples on fresh profiles (twin defaults) and the profiles, left and right."""
    published = PublishedPose(
        lambda left, right: (0.5 * (left + right), right - left),
        10_000,
        (math.inf, math.inf),
        0.1,
        0.4,
    )
    published.restart(0, (0.0, 0.0, 0.0), (0.0, 0.0))
    kw = dict(
        signed_input=False,
        speed_samples="window",
        revolutions_per_sample=1.0,
        sample_latency_us=0,
        brake_stop_us=620_000,
        brake_friction_rpm_s=13.0,
        start_us=500_000,
        sample_gap_us=450_000,
        rest_rpm=10.0,
    )
    return WheelSpeedSamples(published, 0, **{**kw, **options}), published.profiles


def _rpm(profile, t_s):
    return profile.at(t_s * S, profile.segment(t_s * S))


def test_a_start_moves_at_the_commanded_speed_until_its_first_sample():
    samples, (left, right) = _samples()
    samples.command((1, 1), (30.0, 20.0), 0)
    assert (
        _rpm(left, 0.25) == pytest.approx(15.0)
        and _rpm(left, 1.0) == 30.0
        and _rpm(right, 1.0) == 20.0
    )
    assert left.revolutions(0, 2 * S) == pytest.approx(30.0 * 1.75 / 60)  # 0.5 s ramp, then held


def test_a_start_stands_once_its_window_must_have_been_published():
    """No sample after a revolution at the commanded speed: slower than commanded, not further."""
    samples, (left, right) = _samples()
    samples.command((1, 1), (30.0, 30.0), 0)
    assert left.revolutions(0, 10 * S) == pytest.approx(1.0) and _rpm(left, 10.0) == 0.0


def test_the_wheels_of_a_start_keep_the_ratio_of_their_commands():
    """Their windows opened at different times before a stop: both stand-ins end together (no
    yaw)."""
    samples, (left, right) = _samples()
    samples.command((1, 1), (60.0, 60.0), 0)
    samples.sample(0, 60.0, 1 * S)
    samples.sample(1, 60.0, int(1.6 * S))
    samples.command((0, 0), (0.0, 0.0), 2 * S)
    samples.command((-1, 1), (30.0, 30.0), 5 * S)  # in place
    for t_s in (5.2, 6.0, 6.5, 7.0, 7.5, 8.0, 9.0):
        assert _rpm(left, t_s) == pytest.approx(-_rpm(right, t_s))
    assert right.revolutions(5 * S, 9 * S) < 1.0 - right.revolutions(1.825 * S, 5 * S) + 1e-9


def test_a_sample_after_its_due_time_replaces_the_silence_bound():
    """The silence bound's knots are assumptions: a late window is not clipped at them."""
    samples, (left, _) = _samples()
    samples.command((1, 1), (60.0, 60.0), 0)
    samples.sample(0, 60.0, 1 * S)  # the next is due at 2.45 s at 60 RPM
    samples.sample(0, 50.0, int(2.6 * S))  # late: a revolution from 1.4 s
    assert _rpm(left, 2.0) == pytest.approx(50.0)
    assert left.revolutions(1.4 * S, 2.6 * S) == pytest.approx(1.0)


def test_a_revolution_across_a_stop_keeps_its_count_if_its_wheel_stood_when_it_began():
    """The window opened as the brake ended (the estimate has the wheel at rest there): the whole
    revolution is turned after the restart."""
    samples, (left, _) = _samples()
    samples.command((1, 1), (60.0, 60.0), 0)
    samples.sample(0, 60.0, 1 * S)
    samples.command((0, 0), (0.0, 0.0), 1 * S)  # at rest by 1.49 s
    samples.command((1, 1), (60.0, 60.0), 5 * S)
    samples.sample(0, 60.0 / 4.4, 6 * S)  # one revolution from 1.6 s
    assert left.revolutions(5 * S, 6 * S) == pytest.approx(1.0)


def test_a_revolution_across_a_reversal_counts_the_turns_either_way():
    """The SC output counts turns in both directions: those before the stop are done, backward
    after."""
    samples, (left, _) = _samples()
    samples.command((1, 1), (60.0, 60.0), 0)
    samples.sample(0, 60.0, 1 * S)
    samples.command((0, 0), (0.0, 0.0), int(1.5 * S))
    samples.command((-1, -1), (60.0, 60.0), 5 * S)
    samples.sample(0, 60.0 / 4.6, int(5.8 * S))  # one revolution from 1.2 s
    done = left.revolutions(1.2 * S, 5 * S)
    assert 0.4 < done < 0.7
    assert left.revolutions(5 * S, 5.8 * S) == pytest.approx(-(1.0 - done))


def test_a_restart_published_before_its_ramp_ends_goes_on_to_the_commanded_speed():
    samples, (left, _) = _samples()
    samples.command((1, 1), (60.0, 60.0), 0)
    samples.sample(0, 60.0, 1 * S)
    samples.command((0, 0), (0.0, 0.0), int(1.9 * S))
    samples.command((1, 1), (60.0, 60.0), 5 * S)
    samples.sample(
        0, 60.0 / 4.1, int(5.3 * S)
    )  # one revolution from 1.2 s: a little of it after 5 s
    after = left.revolutions(5 * S, 5.3 * S)
    assert 0.0 < after < 0.1
    assert _rpm(left, 5.3) == pytest.approx(2 * after * 60 / 0.3)  # a linear start from rest
    assert _rpm(left, 6.0) == pytest.approx(60.0)


def test_a_slow_wheel_brakes_to_rest_sooner():
    """Shorted phases (time constant 0.31 s) and friction (13 RPM/s): the twin's hub wheels."""
    samples, _ = _samples()
    assert samples.brake_us(10.0) == pytest.approx(0.31 * S, abs=0.02 * S)
    assert samples.brake_us(100.0) == pytest.approx(0.54 * S, abs=0.02 * S)
    assert _samples(brake_friction_rpm_s=0.0)[0].brake_us(10.0) == 620_000


def test_hold_mode_and_signed_input_have_no_stand_in():
    for options in ({"speed_samples": "hold"}, {"signed_input": True}):
        samples, (left, _) = _samples(**options)
        samples.command((1, 1), (30.0, 30.0), 0)
        assert left.revolutions(0, 2 * S) == 0.0
    with pytest.raises(ValueError, match="speed_samples"):
        _samples(speed_samples="guess")


def test_a_wheel_measured_before_the_other_keeps_the_ratio_of_their_speeds():
    """The right wheel's newer sample moves the left one as well (at their ratio at the left's
    sample): no yaw from a fresh speed against a held one."""
    samples, (left, right) = _samples()
    samples.command((1, 1), (60.0, 60.0), 0)
    samples.sample(0, 54.0, int(1.5 * S))  # a revolution from 0.39 s
    samples.sample(1, 60.0, int(1.6 * S))  # from 0.6 s
    samples.sample(1, 66.0, int(2.8 * S))  # the right wheel is faster now
    assert _rpm(right, 2.5) == pytest.approx(66.0)
    assert _rpm(left, 2.5) == pytest.approx(66.0 * _rpm(left, 1.5) / _rpm(right, 1.5))
