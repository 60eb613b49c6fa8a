"""One UMBmark square (experiments/umbmark/square.py): the driver, and the parts of its return
error.

The nominal robot (its odometry's geometry is the true one): with the rigid contact the wheels do
not slip, so the return error is the odometry's own, what it makes of the firmware's speed samples;
with the brush tyres the slip adds its part. The firmware publishing its PI's estimate instead of
the mean since the previous sample (the former default) shows what that choice costs."""

import math
from dataclasses import replace

import numpy as np
import pytest

from amr_twin.controllers.firmware_params import ImprovedParams
from amr_twin.model.config import load_config
from amr_twin.experiments.umbmark.square import Profile, drive_square, wheel_pose
from amr_twin.assembly.twin import Twin, TwinOptions

RIGID = ["wheel.tyre_slip=false"]


def _square(sets, direction="cw", firmware_params=None):
    twin = Twin(
        load_config(sets=sets),
        TwinOptions(
            world="empty",
            firmware="improved",
            visuals=False,
            seed=3,
            firmware_params=firmware_params,
        ),
    )
    return drive_square(twin, direction, Profile())


@pytest.fixture(scope="module")
def squares():
    return {
        "rigid": _square(RIGID),
        "tyres": _square([], "ccw"),
        "estimate": _square(RIGID, firmware_params=replace(ImprovedParams(), publish_mean=False)),
    }


def test_rigid_contact_the_odometry_counts_every_edge(squares):
    """No slip: the wheels' true angles give the pose to a millimetre, and the odometry node, which
    counts the firmware's SC edges (8.7 mm of rim each), comes back within 12 mm."""
    r = squares["rigid"]
    assert math.hypot(*r.wheels_error_m) < 0.002 and r.wheels_error_m == r.slip_error_m
    assert math.hypot(*r.error_m) < 0.012
    assert (
        math.hypot(*r.true_xy_m) < 0.4 and abs(r.true_yaw_deg) < 8.0
    )  # it came back round, turns within 2 deg


def test_the_pi_estimate_published_loses_heading_at_every_start_and_stop(squares):
    """The same square with the firmware publishing its PI's speed estimate (lagging, 0 below 4.4
    RPM): the odometry misses about an edge per wheel at each start and stop, over 10 cm of return
    error where the wheels' angles are still exact."""
    r = squares["estimate"]
    assert math.hypot(*r.wheels_error_m) < 0.002
    assert math.hypot(*r.error_m) > 0.10


def test_with_the_tyres_the_slip_is_most_of_the_error(squares):
    """The nominal robot on brush tyres: its wheels' angles and the true geometry miss the return by
    the tyres' slip and scrub (2-6 cm); the odometry adds less than an edge's worth to it."""
    r = squares["tyres"]
    slip = math.hypot(*r.slip_error_m)
    assert 0.02 < slip < 0.06 and r.wheels_error_m == r.slip_error_m
    assert math.hypot(r.error_m[0] - r.slip_error_m[0], r.error_m[1] - r.slip_error_m[1]) < 0.012


def test_wheel_pose_integrates_arcs():
    """Quarter circles of radius 1 m: 100 increments of the wheels' angles (left 0.76 m, right 1.24
    m of rim) turn the pose by 90 degrees to (1, 1)."""
    r, b = 0.125, 0.48
    steps = np.linspace(0, 1, 101)[:, None] * np.array([0.76 * math.pi / 2, 1.24 * math.pi / 2]) / r
    x, y, yaw = wheel_pose(steps, r, r, b)
    assert (x, y, yaw) == pytest.approx((1.0, 1.0, math.pi / 2), abs=1e-12)


def test_a_bad_direction_is_refused():
    twin = Twin(
        load_config(sets=RIGID), TwinOptions(world="empty", firmware="improved", visuals=False)
    )
    with pytest.raises(ValueError, match="direction"):
        drive_square(twin, "left", Profile())
