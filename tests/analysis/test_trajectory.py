"""ATE / RPE against known answers (amr_twin/analysis/trajectory.py)."""

import math

import numpy as np
import pytest

from amr_twin.analysis import se2
from amr_twin.analysis.trajectory import TrajectoryErrors, align_se2, errors


def _straight(n=201, speed_m_s=1.0, dt_s=0.1, yaw_rad=0.0):
    """A straight path along ``yaw_rad`` at constant speed: t (n,), pose (n, 3)."""
    t = np.arange(n) * dt_s
    d = speed_m_s * t
    return t, np.column_stack([d * math.cos(yaw_rad), d * math.sin(yaw_rad), np.full(n, yaw_rad)])


def _circle(n=400, radius_m=3.0, dt_s=0.05, rate_rad_s=0.3):
    t = np.arange(n) * dt_s
    a = rate_rad_s * t
    return t, np.column_stack([radius_m * np.sin(a), radius_m * (1 - np.cos(a)), se2.wrap_rad(a)])


def test_identical_trajectories_have_zero_errors():
    t, pose = _circle()
    e = errors(t, pose, t, pose)
    assert isinstance(e, TrajectoryErrors)
    assert e.ate_m == pytest.approx(0.0, abs=1e-12)
    assert e.rpe_trans_m == pytest.approx(0.0, abs=1e-12) and e.rpe_rot_deg == pytest.approx(
        0.0, abs=1e-9
    )
    assert e.max_yaw_err_deg == pytest.approx(0.0, abs=1e-9)
    assert e.length_m == pytest.approx(3.0 * 0.3 * t[-1], rel=1e-3)  # arc length r * angle


def test_constant_offset_gives_ate_equal_to_offset_and_zero_when_aligned():
    t, pose = _circle()
    est = pose + np.array([0.3, 0.4, 0.0])
    e = errors(t, est, t, pose)
    assert e.ate_m == pytest.approx(0.5, abs=1e-12)
    assert e.final_pos_err_m == pytest.approx(0.5, abs=1e-12)
    assert e.rpe_trans_m == pytest.approx(0.0, abs=1e-12)  # relative motion is exact
    aligned = errors(t, est, t, pose, align=True)
    assert aligned.ate_m == pytest.approx(0.0, abs=1e-9)


def test_rigidly_moved_trajectory_aligns_back_and_rpe_ignores_the_move():
    t, pose = _circle()
    theta, shift = 0.7, np.array([2.0, -1.0])
    c, s = math.cos(theta), math.sin(theta)
    est = np.column_stack(
        [pose[:, :2] @ np.array([[c, s], [-s, c]]) + shift, se2.wrap_rad(pose[:, 2] + theta)]
    )
    raw = errors(t, est, t, pose)
    assert raw.ate_m > 1.0 and raw.rms_yaw_err_deg == pytest.approx(math.degrees(theta))
    assert raw.rpe_trans_m == pytest.approx(0.0, abs=1e-9) and raw.rpe_rot_deg == pytest.approx(
        0.0, abs=1e-9
    )
    aligned = errors(t, est, t, pose, align=True)
    assert aligned.ate_m == pytest.approx(0.0, abs=1e-9)
    assert aligned.max_yaw_err_deg == pytest.approx(0.0, abs=1e-7)
    rot, back = align_se2(est[:, :2], pose[:, :2])
    assert rot == pytest.approx(-theta)
    assert back == pytest.approx(-np.array([[c, s], [-s, c]]) @ shift)  # p = R^T (est - shift)


@pytest.mark.parametrize("delta_m", [1.0, 3.0])
def test_constant_yaw_rate_error_gives_rpe_rotation_of_rate_times_delta_time(delta_m):
    t, truth = _straight(speed_m_s=0.4)  # 0.04 m a sample: delta_m is a whole number of samples
    rate_rad_s = math.radians(1.0)
    est = truth.copy()
    est[:, 2] += rate_rad_s * t  # heading drifts by 1 deg/s, positions exact
    e = errors(t, est, t, truth, rpe_delta_m=delta_m)
    # evo's pairs: delta_m ahead, and near the end the last sample while it is within 10 % of
    # delta_m (no sample lies on that bound here)
    travel = truth[-1, 0] - truth[:, 0]
    pair_m = np.minimum(travel, delta_m)[travel > 0.9 * delta_m]
    expected_deg = math.sqrt(np.mean((1.0 * pair_m / 0.4) ** 2))
    assert expected_deg < 1.0 * delta_m / 0.4 - 1e-3  # the end pairs are shorter
    assert e.rpe_rot_deg == pytest.approx(expected_deg, rel=1e-6)
    assert e.final_yaw_err_deg == pytest.approx(math.degrees(rate_rad_s * t[-1]), rel=1e-9)
    assert e.max_yaw_err_deg == pytest.approx(e.final_yaw_err_deg)


def test_scale_error_gives_rpe_translation_per_delta():
    t, truth = _straight()
    est = truth.copy()
    est[:, :2] *= 1.02  # odometry 2 % long
    e = errors(t, est, t, truth, rpe_delta_m=1.0)
    assert e.rpe_trans_m == pytest.approx(0.02, rel=1e-6)
    assert e.final_pos_err_m == pytest.approx(0.02 * 20.0, rel=1e-9)
    assert e.ate_m < e.final_pos_err_m


def test_heading_error_across_plus_minus_pi_is_small():
    t, truth = _straight(yaw_rad=math.pi - 0.01)
    est = truth.copy()
    est[:, 2] = -math.pi + 0.01  # 0.02 rad away through the wrap
    e = errors(t, est, t, truth)
    assert e.max_yaw_err_deg == pytest.approx(math.degrees(0.02), rel=1e-6)
    assert e.rpe_rot_deg == pytest.approx(0.0, abs=1e-9)


def test_truth_yaw_is_interpolated_through_the_wrap():
    t_ref = np.array([0.0, 1.0])
    ref = np.array(
        [[0.0, 0.0, math.pi - 0.1], [1.0, 0.0, -math.pi + 0.1]]
    )  # turning +0.2 rad through pi
    mid = se2.interpolate(t_ref, ref, np.array([0.5]))
    assert abs(se2.wrap_rad(mid[0, 2] - math.pi)) == pytest.approx(0.0, abs=1e-12)
    assert mid[0, 0] == pytest.approx(0.5)


def test_estimate_at_other_stamps_is_compared_with_interpolated_truth():
    t, truth = _straight(n=101, dt_s=0.1)  # 1 m/s along x
    t_est = np.linspace(0.05, 9.95, 37)
    est = np.column_stack([t_est + 0.1, np.zeros_like(t_est), np.zeros_like(t_est)])  # 0.1 m ahead
    e = errors(t_est, est, t, truth)
    assert e.ate_m == pytest.approx(0.1, abs=1e-12)
    assert e.length_m == pytest.approx(9.9, abs=1e-9)


def test_samples_outside_the_truth_span_are_left_out():
    t, truth = _straight(n=11)
    t_est = np.array([-5.0, 0.0, 0.5, 1.0, 99.0])
    est = np.column_stack([np.array([50.0, 0.0, 0.5, 1.0, 50.0]), np.zeros(5), np.zeros(5)])
    assert errors(t_est, est, t, truth).ate_m == pytest.approx(0.0, abs=1e-12)


def test_short_path_has_nan_rpe():
    t, truth = _straight(n=5, speed_m_s=0.1)  # 0.04 m in all
    e = errors(t, truth, t, truth, rpe_delta_m=1.0)
    assert math.isnan(e.rpe_trans_m) and math.isnan(e.rpe_rot_deg)
    assert e.ate_m == 0.0


@pytest.mark.parametrize(
    "kwargs, name",
    [
        ({"pose_est": np.zeros((10, 2))}, "pose_est"),
        ({"t_est_s": np.arange(9.0)}, "pose_est"),
        ({"pose_true": np.full((10, 3), np.nan)}, "pose_true"),
        ({"t_true_s": np.array([0, 1, 2, 3, 4, 5, 6, 7, 9, 8.0])}, "t_true_s"),
        ({"t_est_s": np.array([0, 1, 2, np.inf, 4, 5, 6, 7, 8, 9.0])}, "t_est_s"),
        ({"rpe_delta_m": 0.0}, "rpe_delta_m"),
        ({"t_est_s": np.arange(10.0) + 100.0}, "t_est_s"),
    ],
)
def test_bad_input_raises_one_line_value_error_naming_the_argument(kwargs, name):
    t, pose = _straight(n=10)
    args = {"t_est_s": t, "pose_est": pose, "t_true_s": t, "pose_true": pose, **kwargs}
    with pytest.raises(ValueError, match=f"^{name}") as info:
        errors(**args)
    assert "\n" not in str(info.value)


def test_planar_alignment_never_mirrors_the_trajectory():
    # evo's --align (3D Umeyama) can rotate a planar trajectory 180 deg about an axis in the floor,
    # i.e. mirror it, and so scores a mirrored estimate as perfect; a robot on the floor cannot do
    # that
    t, pose = _circle()
    mirrored = np.column_stack([pose[:, 0], -pose[:, 1], -pose[:, 2]])
    assert errors(t, mirrored, t, pose, align=True).ate_m > 1.0
    evo = pytest.importorskip("evo")
    from evo.core.trajectory import PoseTrajectory3D

    def traj(p):
        xyz = np.column_stack([p[:, :2], np.zeros(len(p))])
        quat = np.column_stack(
            [np.cos(p[:, 2] / 2), np.zeros((len(p), 2)), np.sin(p[:, 2] / 2)]
        )  # w x y z
        return PoseTrajectory3D(xyz, quat, t)

    est = traj(mirrored)
    est.align(traj(pose), correct_scale=False)
    assert np.abs(est.positions_xyz[:, :2] - pose[:, :2]).max() < 1e-6, (
        evo.__name__
    )  # evo: mirrored onto truth
