"""LiDAR odometry: SE(2) helpers, scan points, synthetic room scans (no mujoco), then twin scans.

The synthetic scans are cast analytically in a rectangular room from the laser pose
at each beam's own instant (0.5 ms apart, as the twin's RPLIDAR), so a moving robot
gives distorted scans that only a correct deskew straightens.
"""

import math

import numpy as np
import pytest

from amr_twin.analysis import se2
from amr_twin.estimation.lidar_odometry import (
    LidarOdometry,
    beam_times_s,
    scan_end_time_s,
    scan_points,
)
from amr_twin.ros.messages import Header, Time
from amr_twin.ros.sensor_messages import LaserScan
from amr_twin.recording.recorder import attach_recorder, recorder_of

ROOM = (-4.0, 6.0, -3.0, 2.5)  # inner faces x_min, x_max, y_min, y_max, m
LASER = (0.30, 0.0, 0.0)
N_BEAMS, BEAM_DT_S = 364, 0.0005


def room_scan(
    base_pose_at, t0_s: float, rng: np.random.Generator, noise_m: float = 0.005
) -> LaserScan:
    """A scan of ROOM whose beam i is cast at t0 + i * BEAM_DT_S from the laser pose then."""
    t = t0_s + BEAM_DT_S * np.arange(N_BEAMS)
    laser = se2.compose(np.array([base_pose_at(ti) for ti in t]), np.array(LASER))
    inc = 2 * math.pi / N_BEAMS
    ang = laser[:, 2] - math.pi + inc * np.arange(N_BEAMS)
    c, s = np.cos(ang), np.sin(ang)
    x0, x1, y0, y1 = ROOM
    with np.errstate(divide="ignore"):
        tx = np.where(c > 0, (x1 - laser[:, 0]) / c, (x0 - laser[:, 0]) / c)
        ty = np.where(s > 0, (y1 - laser[:, 1]) / s, (y0 - laser[:, 1]) / s)
    r = np.minimum(np.where(tx > 0, tx, np.inf), np.where(ty > 0, ty, np.inf))
    r = r + noise_m * rng.standard_normal(N_BEAMS)
    return LaserScan(
        header=Header(0, Time.from_sec(t0_s), "laser"),
        angle_min=-math.pi,
        angle_max=-math.pi + inc * (N_BEAMS - 1),
        angle_increment=inc,
        time_increment=BEAM_DT_S,
        scan_time=N_BEAMS * BEAM_DT_S,
        range_min=0.15,
        range_max=12.0,
        ranges=r.astype(np.float32),
    )


def drive_pose(t_s: float) -> np.ndarray:
    """Base pose: 0.8 m/s along x for 3 s, then an arc at 0.6 rad/s (about 23 cm and 6 deg per
    scan)."""
    if t_s <= 3.0:
        return np.array([-2.5 + 0.8 * t_s, -1.0, 0.0])
    dt = t_s - 3.0
    radius = 0.8 / 0.6
    return np.array(
        [-0.1 + radius * math.sin(0.6 * dt), -1.0 + radius * (1 - math.cos(0.6 * dt)), 0.6 * dt]
    )


def run_synthetic(deskew: bool, prior: bool, duration_s: float = 5.0, seed: int = 3):
    """Register a synthetic drive; return the ATE (m) and the max yaw error (rad) against the
    truth."""
    rng = np.random.default_rng(seed)
    lo = LidarOdometry(voxel_size_m=0.15, deskew=deskew)
    t0 = 0.0
    while t0 + N_BEAMS * BEAM_DT_S < duration_s:
        scan = room_scan(drive_pose, t0, rng)
        t_a, t_b = lo.prior_interval_s(scan)
        lo.register(scan, tuple(se2.between(drive_pose(t_a), drive_pose(t_b))) if prior else None)
        t0 += N_BEAMS * BEAM_DT_S
    t_s, pose = lo.poses(origin_xy_yaw=tuple(drive_pose(lo.poses()[0][0])))
    truth = np.array([drive_pose(t) for t in t_s])
    err = np.hypot(*(pose[:, :2] - truth[:, :2]).T)
    yaw_err = np.abs(np.angle(np.exp(1j * (pose[:, 2] - truth[:, 2]))))
    return float(np.sqrt(np.mean(err**2))), float(yaw_err.max())


# -- pure helpers ---------------------------------------------------------------------
def test_scan_points_drop_invalid_beams_and_times_follow_the_beams():
    r = np.array([1.0, np.inf, 0.1, 2.0, np.nan, 13.0], np.float32)
    scan = LaserScan(
        header=Header(0, Time.from_us(2_000_000), "laser"),
        angle_min=0.0,
        angle_increment=math.pi / 2,
        time_increment=0.001,
        range_min=0.15,
        range_max=12.0,
        ranges=r,
    )
    points, index = scan_points(scan)
    assert index.tolist() == [0, 3]
    np.testing.assert_allclose(
        points, [[1.0, 0.0, 0.0], [0.0, -2.0, 0.0]], atol=1e-6
    )  # beam 3 at 270 deg
    np.testing.assert_allclose(beam_times_s(scan), 2.0 + 0.001 * np.arange(6))
    assert scan_end_time_s(scan) == pytest.approx(2.005)


def test_bad_parameters_and_time_going_back_are_refused():
    with pytest.raises(ValueError, match="voxel_size_m"):
        LidarOdometry(voxel_size_m=0.0)
    with pytest.raises(ValueError, match="min_range_m"):
        LidarOdometry(min_range_m=5.0, max_range_m=2.0)
    lo = LidarOdometry()
    rng = np.random.default_rng(0)
    lo.register(room_scan(drive_pose, 1.0, rng))
    with pytest.raises(ValueError, match="prior_base_delta"):
        lo.register(room_scan(drive_pose, 1.2, rng), (0.1, 0.0))
    with pytest.raises(ValueError, match="prior_base_delta"):
        lo.register(room_scan(drive_pose, 1.2, rng), (0.1, math.nan, 0.0))
    with pytest.raises(ValueError, match="scan stamp"):
        lo.register(room_scan(drive_pose, 0.5, rng))


# -- synthetic room -------------------------------------------------------------------
def test_first_scan_is_the_origin_and_a_static_robot_stays_there():
    rng = np.random.default_rng(1)
    lo = LidarOdometry()

    def still(t):
        return np.array([0.3, 0.2, 0.4])

    assert lo.register(room_scan(still, 0.0, rng)) == pytest.approx((0.0, 0.0, 0.0), abs=1e-12)
    for k in range(1, 6):
        lo.register(room_scan(still, 0.182 * k, rng), (0.0, 0.0, 0.0))
    _, pose = lo.poses()
    assert np.abs(pose[:, :2]).max() < 0.005 and np.abs(pose[:, 2]).max() < math.radians(0.2)


def test_prior_interval_spans_from_the_previous_scan_end_or_one_rotation():
    rng = np.random.default_rng(4)
    lo = LidarOdometry()
    first = room_scan(drive_pose, 1.0, rng)
    assert lo.prior_interval_s(first) == pytest.approx(
        (scan_end_time_s(first) - N_BEAMS * BEAM_DT_S, scan_end_time_s(first))
    )
    lo.register(first)
    second = room_scan(drive_pose, 1.182, rng)
    assert lo.prior_interval_s(second) == (scan_end_time_s(first), scan_end_time_s(second))


def test_spin_in_place_keeps_base_link_still_not_the_laser():
    # the laser, 0.30 m ahead, sweeps a circle; base_link must stay at the origin. The
    # first scan is smeared by 12.5 deg too: without its deskew every pose is ~10 cm off.
    rng = np.random.default_rng(2)

    def spin(t):  # 1.2 rad/s: 12.5 deg per scan
        return np.array([0.5, -0.5, 1.2 * t])

    lo = LidarOdometry()
    for k in range(12):
        scan = room_scan(spin, 0.182 * k, rng)
        t_a, t_b = lo.prior_interval_s(scan)
        pose = lo.register(scan, tuple(se2.between(spin(t_a), spin(t_b))))
        if k == 0:
            assert pose == pytest.approx((0.0, 0.0, 0.0), abs=1e-12)
    t_s, pose = lo.poses()
    assert np.abs(pose[:, :2]).max() < 0.01
    assert pose[-1, 2] == pytest.approx(1.2 * (t_s[-1] - t_s[0]), abs=math.radians(0.5))
    laser = lo.beam_laser_poses(scan)
    assert laser.shape == (N_BEAMS, 3)
    np.testing.assert_allclose(
        np.hypot(laser[:, 0], laser[:, 1]), 0.30, atol=0.01
    )  # on the laser's circle


def test_synthetic_drive_with_prior_and_deskew_is_accurate_and_deskew_matters():
    ate_m, yaw_max_rad = run_synthetic(deskew=True, prior=True)
    assert ate_m < 0.015 and yaw_max_rad < math.radians(1.5)  # measured 4.5 mm, 0.9 deg
    ate_raw_m, _ = run_synthetic(deskew=False, prior=True)
    assert ate_raw_m > 3 * ate_m  # 15 cm of motion per rotation smears an uncorrected scan (37 mm)
    ate_no_prior_m, _ = run_synthetic(deskew=True, prior=False)
    assert ate_no_prior_m > 3 * ate_m  # KISS-ICP's constant velocity lags the arc (63 mm)


# -- twin scans ---------------------------------------------------------------------
@pytest.fixture(scope="module")
def warehouse_drive():
    """18 s in the warehouse: 0.8 m/s east along the south of the aisle, a U-turn of radius 1.5 m,
    back west."""
    from amr_twin.model.config import load_config
    from amr_twin.assembly.twin import Twin, TwinOptions

    twin = Twin(
        load_config(),
        TwinOptions(
            sensors=("imu", "lidar"),
            firmware="improved",
            world="warehouse",
            start_xy_yaw=(-6.5, -1.5, 0.0),
        ),
    )
    attach_recorder(twin)
    scans, odom = [], []
    twin.bus.subscribe("scan", scans.append)
    twin.bus.subscribe("odom", odom.append)
    for t_s, send in (
        (0.0, lambda: twin.client.linear(0.8)),
        (8.0, lambda: twin.client.angular(30.0, 1.5)),
        (14.0, lambda: twin.client.linear(0.8)),
    ):
        twin.advance_to_us(int(t_s * 1e6))
        assert send() == 0
    twin.advance_to_us(18_000_000)
    series = recorder_of(twin).series()
    t_odom = np.array([m.header.stamp.to_sec() for m in odom])
    pose_odom = np.array(
        [
            (m.pose.pose.position.x, m.pose.pose.position.y, m.pose.pose.orientation.yaw_rad())
            for m in odom
        ]
    )
    return scans, t_odom, pose_odom, series.t_s, series.pose


def test_twin_drive_lidar_odometry_ate_well_under_10_cm(warehouse_drive):
    scans, t_odom, pose_odom, t_true, pose_true = warehouse_drive
    lo = LidarOdometry(
        voxel_size_m=0.15, max_range_m=12.0, min_range_m=0.15, laser_in_base_xy_yaw=LASER
    )
    for scan in scans:
        t_a, t_b = lo.prior_interval_s(scan)
        prior = se2.between(
            se2.interpolate(t_odom, pose_odom, t_a), se2.interpolate(t_odom, pose_odom, t_b)
        )
        lo.register(scan, tuple(prior))
    t_s, _ = lo.poses()
    _, pose = lo.poses(origin_xy_yaw=tuple(se2.interpolate(t_true, pose_true, t_s[0])))
    truth = se2.interpolate(t_true, pose_true, t_s)
    err = np.hypot(*(pose[:, :2] - truth[:, :2]).T)
    yaw_err = np.abs(np.angle(np.exp(1j * (pose[:, 2] - truth[:, 2]))))
    assert len(scans) >= 95 and lo.skipped == 0
    assert (
        np.hypot(*(truth[-1, :2] - truth[0, :2])) > 2.5 and abs(truth[-1, 2]) > 3.0
    )  # it did drive and turn
    assert float(np.sqrt(np.mean(err**2))) < 0.05  # measured 19 mm
    assert err.max() < 0.08 and yaw_err.max() < math.radians(2.0)
