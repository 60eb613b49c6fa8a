"""The EKF's inputs: an odometry message's twist, the gyro's rest calibration, the UWB anchors'
geometry and range Jacobian (no mujoco)."""

import numpy as np
import pytest

from amr_twin.estimation.ekf_filter import initial_filter
from amr_twin.estimation.ekf_inputs import AnchorGeometry, GyroRestCalibration, OdometryTwist
from amr_twin.estimation.ekf_model import BG
from amr_twin.model.config import load_config
from amr_twin.ros.geometry_messages import (
    Odometry,
    Point,
    Pose,
    PoseWithCovariance,
    Quaternion,
    Twist,
    TwistWithCovariance,
    Vector3,
)
from amr_twin.ros.messages import Header, Time

CFG = load_config()


def _odom(t_s: float, x_m: float, yaw_rad: float) -> Odometry:
    return Odometry(
        header=Header(0, Time.from_sec(t_s), "odom"),
        pose=PoseWithCovariance(Pose(Point(x_m, 0.0, 0.0), Quaternion.from_yaw(yaw_rad))),
        twist=TwistWithCovariance(Twist(Vector3(1.0, 0, 0), Vector3(0, 0, 0.2))),
    )


def test_the_twist_is_the_messages_or_its_poses_differentiated():
    assert OdometryTwist(False)(_odom(0.0, 0.0, 0.0)) == (1.0, 0.2)
    twist = OdometryTwist(True)
    assert twist(_odom(0.0, 0.0, 0.0)) is None  # nothing to differentiate against
    v, w = twist(_odom(0.1, 0.05, 0.01))
    assert v == pytest.approx(0.5, rel=1e-3) and w == pytest.approx(0.1, rel=1e-6)
    assert twist(_odom(0.1, 0.07, 0.01)) is None  # a repeated stamp


def test_the_gyro_bias_is_the_mean_of_the_rates_at_rest():
    cal = GyroRestCalibration(CFG.ekf, 0.24)
    rest, moving = (0.0, 0.0), (0.5, 0.0)
    assert not cal.done and CFG.ekf.imu_rest_calibration_s > 0.2
    assert cal.take(0.0, 0.010, rest) and cal.take(0.1, 0.020, rest)
    assert not cal.take(0.2, 0.5, moving)  # moving: over
    f = initial_filter(CFG.ekf, np.zeros(3))
    cal.finish(f)
    assert cal.done and f.x[BG, 0] == pytest.approx(0.015)
    assert f.P[BG, BG] == pytest.approx(CFG.ekf.gyro_w_sigma_rad_s**2 / 2)
    assert np.all(f.P[BG, :BG] == 0.0)


def test_a_yaw_rate_is_at_rest_by_its_wheels_speed_on_the_track():
    cal = GyroRestCalibration(CFG.ekf, 0.25)
    w = CFG.ekf.rest_speed_m_s / 0.25
    assert cal.at_rest((0.0, 0.99 * w)) and not cal.at_rest((0.0, 1.01 * w))


def test_the_anchors_come_from_the_uwb_section_and_an_unknown_one_is_refused():
    geometry = AnchorGeometry(use_uwb=True, uwb=CFG.uwb)
    assert np.array_equal(geometry.anchors_xy_m, CFG.uwb.anchors_xy_m)
    assert geometry.dz_m == pytest.approx(CFG.uwb.anchor_z_m - CFG.uwb.tag_pos_m[2])
    assert geometry.index("uwb_anchor_3") == 3
    with pytest.raises(ValueError, match=r"anchor 4 not in \[0, 3\]"):
        geometry.index("uwb_anchor_4")
    with pytest.raises(ValueError, match="anchors_xy_m: needed"):
        AnchorGeometry(use_uwb=True)


def test_range_jacobian_matches_finite_differences():
    geometry = AnchorGeometry(use_uwb=True, uwb=CFG.uwb)
    x = np.array([1.0, -2.0, 0.7, 0.5, 0.1, 0.0])
    r, H = geometry.model(x, 1)
    for i in range(3):
        dx = np.zeros(6)
        dx[i] = 1e-6
        assert (geometry.model(x + dx, 1)[0] - r) / 1e-6 == pytest.approx(H[0, i], abs=1e-5)
    assert np.all(H[0, 3:] == 0.0)
