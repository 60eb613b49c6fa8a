"""The C form of ``integrate`` gives its Python twin's poses to the bit."""

import random

import pytest

from amr_twin.estimation.dead_reckoning import integrate
from amr_twin.estimation.drive_arcs import DriveGeometry, arc_kernel
from amr_twin.estimation.published_pose import PublishedPose
from amr_twin.estimation.speed_profile import SpeedProfile

GEOMETRY = DriveGeometry(0.1251, 0.1249, 0.4803)


def _profile(rng: random.Random, t0_us: int) -> SpeedProfile:
    """Knots as the odometry node makes them: steps, ramps, windows, repeated instants."""
    p = SpeedProfile(t0_us, rng.uniform(-60.0, 60.0))
    t = t0_us
    for _ in range(rng.randrange(0, 12)):
        t += rng.choice((0, 1, 7_000, 23_456, 180_000))
        kind = rng.randrange(3)
        if kind == 0:
            p.step(t, rng.choice((p.last_rpm, 0.0, rng.uniform(-60.0, 60.0))))
        elif kind == 1:
            p.point(t, rng.choice((p.last_rpm, rng.uniform(-60.0, 60.0))))
        else:
            p.window(t - 5_000, t, rng.uniform(-60.0, 60.0))
    return p


def test_c_integrate_gives_the_python_twins_bits():
    if arc_kernel() is None:
        pytest.skip("no C compiler: the Python twin runs")
    rng = random.Random(7)
    checked = 0
    for _ in range(400):
        t0 = rng.randrange(0, 2_000_000)
        profiles = [_profile(rng, t0), _profile(rng, t0)]
        start = (
            t0 + rng.choice((0, 3_000)),
            rng.uniform(-5, 5),
            rng.uniform(-5, 5),
            rng.uniform(-9, 9),
        )
        t_end = start[0] + rng.choice((0, 1, 9_999, 10_000, 250_001, 1_500_000))
        substep = rng.choice((1_000, 10_000, 33_333))
        c = integrate(profiles, start, t_end, substep, GEOMETRY)
        python = integrate(profiles, start, t_end, substep, GEOMETRY, native=False)
        assert c == python, (start, t_end, substep)
        checked += c != (t_end, *start[1:])
    assert checked > 300  # most cases moved the pose


def test_nearly_straight_arcs_give_the_python_twins_bits():
    """Turns below 1e-9 rad an arc take the midpoint step in both twins."""
    if arc_kernel() is None:
        pytest.skip("no C compiler: the Python twin runs")
    geometry = DriveGeometry(0.125, 0.125, 0.48)
    for tiny in (0.0, 1e-12, 3e-10, 2e-9, 1e-7):
        p = [SpeedProfile(0, 30.0), SpeedProfile(0, 30.0 + tiny)]
        p[1].point(80_000, 31.0 + tiny)
        p[0].point(80_000, 31.0)
        start = (0, 1.0, 2.0, 0.3)
        c = integrate(p, start, 95_000, 10_000, geometry)
        assert c == integrate(p, start, 95_000, 10_000, geometry, native=False), tiny


def test_straight_and_turning_arcs_are_kept_apart():
    """Equal speeds drive straight along the heading (the midpoint branch of both twins)."""
    p = [SpeedProfile(0, 30.0), SpeedProfile(0, 30.0)]
    geometry = DriveGeometry(0.125, 0.125, 0.48)
    _t, x, y, yaw = integrate(p, (0, 0.0, 0.0, 0.0), 2_000_000, 10_000, geometry)
    assert (y, yaw) == (0.0, 0.0) and x == pytest.approx(2 * 30.0 / 60.0 * 2 * 3.14159265 * 0.125)


def _published(native: bool) -> PublishedPose:
    pose = PublishedPose(GEOMETRY, 10_000, (3e-5, 2.5e-5), 0.2, 0.4, native=native)
    pose.restart(0, (0.5, -1.0, 0.2), (0.0, 0.0))
    return pose


def test_c_advance_gives_the_python_twins_bits():
    """The published pose, fed the same samples, the same after every step in C and in Python:
    while it catches up (substeps) and once it has (one arc a piece)."""
    if arc_kernel() is None:
        pytest.skip("no C compiler: the Python twin runs")
    rng = random.Random(11)
    c, python = _published(True), _published(False)
    now, settled = 0, 0
    for _ in range(60):
        wheel, rpm = rng.randrange(2), rng.choice((0.0, rng.uniform(-60.0, 60.0)))
        t_end = now + rng.choice((0, 40_000, 300_000))
        for pose in (c, python):
            pose.advance(now)
            pose.profiles[wheel].cut(now)
            pose.profiles[wheel].point(t_end, rpm)
            pose.changed()
        for _k in range(rng.randrange(5, 150)):
            now += rng.choice((1, 3_000, 20_000, 20_000, 115_000))
            settled += c.correction == (0.0, 0.0, 0.0)
            c.advance(now)
            python.advance(now)
            assert (c.pose, c.used, c.correction) == (python.pose, python.used, python.correction)
    assert settled > 200 and c.pose != (0.5, -1.0, 0.2)
