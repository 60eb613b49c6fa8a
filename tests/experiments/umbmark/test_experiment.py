"""UMBmark's arithmetic (experiments/umbmark/experiment.py) against a hand case and an independent
kinematic robot.

The kinematic robot below is written here, not taken from the code under test: a differential
drive with true wheel radii and wheelbase, driven round a square by an odometry that assumes
others (straight until the odometry has 4 m, then in place until it has 90 degrees), integrated
exactly (arcs). Its return errors must give back the true geometry's E_d and E_b.
"""

import math

import pytest

from amr_twin.controllers.odometry_calibration import OdometryCalibration
from amr_twin.experiments.umbmark.experiment import calibration, cluster, umbmark

R_NOM, B_NOM, SIDE = 0.125, 0.48, 4.0


def _square(r_left, r_right, b_true, ccw: bool, odo=(R_NOM, R_NOM, B_NOM)) -> tuple[float, float]:
    """Return error (true - odometry) of an exact kinematic square, m."""
    true = [0.0, 0.0, 0.0]
    est = [0.0, 0.0, 0.0]

    def move(dl, dr):  # wheel angles, rad
        for pose, rl, rr, b in ((true, r_left, r_right, b_true), (est, *odo)):
            sl, sr = dl * rl, dr * rr
            ds, dth = 0.5 * (sl + sr), (sr - sl) / b
            if abs(dth) < 1e-12:
                pose[0] += ds * math.cos(pose[2])
                pose[1] += ds * math.sin(pose[2])
            else:
                rad = ds / dth
                pose[0] += rad * (math.sin(pose[2] + dth) - math.sin(pose[2]))
                pose[1] -= rad * (math.cos(pose[2] + dth) - math.cos(pose[2]))
            pose[2] += dth

    sign = 1.0 if ccw else -1.0
    for _ in range(4):
        move(SIDE / odo[0], SIDE / odo[1])  # the odometry's straight 4 m
        ang = sign * (math.pi / 2) * odo[2] / 2  # the odometry's 90 degrees in place
        move(-ang / odo[0], ang / odo[1])
    return true[0] - est[0], true[1] - est[1]


def test_a_hand_case():
    """alpha = 0.01 rad, beta = 0.002 rad: e_ccw = (2L(a+b), -2L(a+b)) = (0.096, -0.096) m and
    e_cw = (2L(a-b), 2L(a-b)) = (0.064, 0.064) m; R = 2 / sin(0.001) = 2000.0003 m, E_d =
    (R + 0.24) / (R - 0.24) = 1.000240; E_b = 90 / (90 + 0.572958) = 0.993674."""
    res = umbmark([(0.064, 0.064)] * 5, [(0.096, -0.096)] * 5, SIDE, B_NOM)
    assert res.alpha_rad == pytest.approx(0.010, rel=1e-9)
    assert res.beta_rad == pytest.approx(0.002, rel=1e-9)
    assert res.e_d == pytest.approx(1.000240, abs=2e-7)
    assert res.e_b == pytest.approx(0.993674, abs=2e-6)
    assert res.e_max_syst_m == pytest.approx(math.hypot(0.096, 0.096))
    assert res.ccw.r_cg_m == pytest.approx(0.135765, abs=1e-6) and res.cw.r_cg_m == pytest.approx(
        0.090510, abs=1e-6
    )
    assert res.e_nonsyst_rms_m == 0.0


def test_the_spread_is_the_distance_from_the_centre_of_gravity():
    c = cluster("cw", [(0.1, 0.0), (-0.1, 0.0), (0.0, 0.3)])
    assert (c.x_cg_m, c.y_cg_m) == pytest.approx((0.0, 0.1))
    assert c.spread_max_m == pytest.approx(0.2)
    assert c.spread_rms_m == pytest.approx(math.sqrt((2 * (0.01 + 0.01) + 0.04) / 3))


@pytest.mark.parametrize(
    "r_left, r_right, b_true",
    [(0.1249, 0.1251, 0.48), (0.125, 0.125, 0.486), (0.1252, 0.1249, 0.475)],
)
def test_the_calibration_recovers_the_true_geometry(r_left, r_right, b_true):
    cw = _square(r_left, r_right, b_true, ccw=False)
    ccw = _square(r_left, r_right, b_true, ccw=True)
    res = umbmark([cw], [ccw], SIDE, B_NOM)
    assert res.e_d == pytest.approx(r_right / r_left, abs=5e-5)
    assert res.e_b == pytest.approx(b_true / B_NOM, abs=2e-3)
    cal = calibration(res, OdometryCalibration(R_NOM, R_NOM, B_NOM))
    odo = (cal.left_wheel_radius_m, cal.right_wheel_radius_m, cal.wheel_separation_m)
    after = [math.hypot(*_square(r_left, r_right, b_true, ccw=d, odo=odo)) for d in (False, True)]
    assert max(after) < 0.1 * max(math.hypot(*cw), math.hypot(*ccw))  # an order of magnitude
