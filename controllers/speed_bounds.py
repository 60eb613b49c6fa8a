"""What a wheel's speed profile is assumed to do where no sample tells: a start from rest that
gives a measured mean (:func:`start_ramp`) and, after a sample, the silence bound
(:func:`silence_bound`); written on a :class:`~amr_twin.estimation.speed_profile.SpeedProfile`.

Reasons and measurements: docs/explanation/firmware.md#amr_twincontrollerswheel_speed_samples."""

from __future__ import annotations

import math

from amr_twin.estimation.speed_profile import SpeedProfile

SILENCE_KNOT_RATIO = 1.25
"""Ratio of the times since a sample of two knots of the silence bound."""
SILENCE_KNOTS = 64
"""Most knots of the silence bound (``rest_rpm`` 0: the bound then holds the last one, ~1e-6 of the
speed)."""


def start_ramp(
    profile: SpeedProfile,
    t0_us: int,
    t1_us: int,
    mean_rpm: float,
    start_us: int,
    commanded_rpm: float,
) -> None:
    """The wheel stood at ``t0_us`` and averaged ``mean_rpm`` up to ``t1_us``: a linear start.

    A ramp over ``start_us`` to the speed that gives this mean, held after; if the time is
    shorter than the ramp, a ramp to twice the mean, on at that rate up to ``commanded_rpm``.
    """
    duration_us = t1_us - t0_us
    profile.cut(t0_us)
    profile.step(t0_us, 0.0)
    if duration_us > start_us:
        speed = mean_rpm * duration_us / (duration_us - 0.5 * start_us)
        profile.point(t0_us + start_us, speed)
        profile.point(t1_us, speed)
        return
    profile.point(t1_us, 2.0 * mean_rpm)
    commanded = commanded_rpm
    # still starting: on at that rate to the commanded speed
    if commanded > 2.0 * abs(mean_rpm) > 0.0:
        reached_us = t0_us + duration_us * commanded / (2.0 * abs(mean_rpm))
        profile.point(reached_us, math.copysign(commanded, mean_rpm))


def silence_bound(
    profile: SpeedProfile,
    sample_us: int | None,
    sample_gap_us: float,
    revolutions_per_sample: float,
    rest_rpm: float,
) -> None:
    """Assume the wheel's speed after its newest knot from the time since its newest sample.

    A firmware that publishes at least once every ``revolutions_per_sample`` revolutions, a gap
    of up to ``sample_gap_us`` after each sample (the newest ended at ``sample_us``), has turned
    less than that since ``gap`` after its newest sample if no other came: its mean speed since is
    below ``60 * revolutions_per_sample / (elapsed - gap)`` RPM. The speed in force is held until
    the next sample is due at that speed, then kept under this bound, and is 0 (at rest) once the
    bound falls below ``rest_rpm``.
    """
    t_us = sample_us
    held = profile.last_rpm
    if t_us is None or held == 0.0 or not math.isfinite(sample_gap_us):
        return
    # what follows is assumed: a sample after its due time is not clipped
    if profile.assumed_us is None:
        profile.assumed_us = profile.last_us
    rev_us, start = revolutions_per_sample * 60e6, t_us + sample_gap_us
    speed, sign = abs(held), math.copysign(1.0, held)
    t = max(start + rev_us / speed, profile.last_us)  # the next sample at this speed is due by then
    rest_us = start + rev_us / rest_rpm if rest_rpm > 0 else math.inf
    for _ in range(SILENCE_KNOTS):
        if t >= rest_us:
            break
        profile.point(t, sign * min(speed, rev_us / (t - start)))
        t = start + SILENCE_KNOT_RATIO * (t - start)
    if math.isfinite(rest_us):
        rest_us = max(int(rest_us), profile.last_us)
        profile.point(rest_us, sign * min(speed, rest_rpm))
        profile.step(rest_us, 0.0)
