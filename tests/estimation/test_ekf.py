"""EKF on synthetic data: heading with the gyro, UWB bounding the drift, gating, seeds, bus (no
mujoco)."""

import math

import numpy as np
import pytest
from filterpy.kalman import ExtendedKalmanFilter

from amr_twin.ros.bus import Bus
from amr_twin.base.clock import VirtualClock
from amr_twin.model.config import load_config
from amr_twin.estimation import ekf_filter
from amr_twin.estimation.ekf import EkfNode
from amr_twin.estimation.ekf_model import predict_mean
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
from amr_twin.ros.sensor_messages import Imu, Range
from amr_twin.sensors.uwb import simulate_ranges, tag_positions_m

CFG = load_config()
DT_S = 0.01


def _route():
    """Truth at 100 Hz: stand 2 s, then a 36 m loop of straights and 90 deg turns."""
    segments = [(2.0, 0.0, 0.0)]
    for length_m in (10.0, 5.0, 10.0, 5.0):
        segments += [(1.0, 0.5, 0.0), (length_m - 1.0, 1.0, 0.0), (math.pi / 2 / 0.8, 0.3, 0.8)]
    t, pose, vw = [0.0], [(0.0, 0.0, 0.0)], []
    for duration_s, v, w in segments:
        for _ in range(int(round(duration_s / DT_S))):
            x, y, yaw = pose[-1]
            mid = yaw + 0.5 * w * DT_S
            pose.append(
                (x + v * DT_S * math.cos(mid), y + v * DT_S * math.sin(mid), yaw + w * DT_S)
            )
            t.append(t[-1] + DT_S)
            vw.append((v, w))
    vw.append(vw[-1])
    return np.array(t), np.array(pose), np.array(vw)


T_S, POSE, VW = _route()


def _messages(
    seed: int, yaw_rate_scale: float = 1.05, gyro_bias_rad_s: float = 0.1, uwb: bool = True
):
    """(stamp, kind, msg) in stamp order: odom 50 Hz with a yaw-rate scale error (slip), gyro 100 Hz
    with a turn-on bias, walk, scale error and noise, UWB round-robin at 33 Hz."""
    rng = np.random.default_rng(seed)
    out = []
    x = y = yaw = 0.0
    for k in range(
        0, len(T_S), 2
    ):  # dead reckoning of the erroneous wheel speeds, as WheelOdometry
        v, w = VW[k]
        moving = v != 0.0
        v_odom = v * 1.01 + moving * rng.normal(0, 0.01)
        w_odom = w * yaw_rate_scale + moving * rng.normal(0, 0.01)
        pose = Pose(Point(x, y, 0.0), Quaternion.from_yaw(yaw))
        twist = Twist(Vector3(v_odom, 0.0, 0.0), Vector3(0.0, 0.0, w_odom))
        out.append(
            (
                T_S[k],
                0,
                Odometry(
                    header=Header(k, Time.from_sec(T_S[k]), "odom"),
                    pose=PoseWithCovariance(pose),
                    twist=TwistWithCovariance(twist),
                ),
            )
        )
        dt = 2 * DT_S
        x += v_odom * dt * math.cos(yaw + 0.5 * w_odom * dt)
        y += v_odom * dt * math.sin(yaw + 0.5 * w_odom * dt)
        yaw += w_odom * dt
    bias = gyro_bias_rad_s
    for k in range(len(T_S)):
        bias += rng.normal(0.0, 5e-5 * math.sqrt(DT_S))
        gz = VW[k][1] * 1.003 + bias + rng.normal(0.0, 0.0052)
        out.append(
            (
                T_S[k],
                1,
                Imu(
                    header=Header(k, Time.from_sec(T_S[k]), "imu_link"),
                    angular_velocity=Vector3(0.0, 0.0, gz),
                ),
            )
        )
    if uwb:
        k = np.arange(0, len(T_S), 3)
        tag = tag_positions_m(POSE[k], CFG.uwb.tag_pos_m)
        for m in simulate_ranges(
            T_S[k], tag, CFG.uwb.anchors_xy_m, CFG.uwb, rng, anchor=np.arange(len(k)) % 4
        ):
            out.append((m.header.stamp.to_sec(), 2, m))
    out.sort(key=lambda item: (item[0], item[1]))
    return out


def _run(msgs, **kwargs) -> EkfNode:
    node = EkfNode(CFG.ekf, wheel_separation_m=CFG.wheel.separation_m, uwb=CFG.uwb, **kwargs)
    for _, kind, msg in msgs:
        (node.on_odom, node.on_imu, node.on_range)[kind](msg)
    return node


def _errors(node):
    """(position errors (N,), yaw errors (N,) rad) against the truth at the history's stamps."""
    t, pose = node.history()
    true = np.column_stack([np.interp(t, T_S, POSE[:, i]) for i in range(3)])
    dyaw = np.angle(np.exp(1j * (pose[:, 2] - true[:, 2])))
    return np.hypot(pose[:, 0] - true[:, 0], pose[:, 1] - true[:, 1]), dyaw


@pytest.fixture(scope="module")
def runs():
    msgs = _messages(0)
    return {
        name: _run(msgs, use_imu=imu, use_uwb=uwb)
        for name, imu, uwb in (
            ("odom", False, False),
            ("imu", True, False),
            ("uwb", False, True),
            ("uwb_imu", True, True),
        )
    }


def test_odom_plus_imu_beats_odometry_on_heading(runs):
    _, yaw_odom = _errors(runs["odom"])
    _, yaw_imu = _errors(runs["imu"])
    rms_odom, rms_imu = (np.sqrt(np.mean(e**2)) for e in (yaw_odom, yaw_imu))
    assert math.degrees(abs(yaw_odom[-1])) > 10.0  # 5 % yaw-rate error over 360 deg of turns
    assert abs(yaw_imu[-1]) < 0.4 * abs(yaw_odom[-1])
    assert rms_imu < 0.4 * rms_odom


def test_rest_calibration_removes_the_gyro_bias(runs):
    node = runs["imu"]
    assert node.gyro_rest.done
    assert node.state[5] == pytest.approx(0.1, abs=0.003)  # the 0.1 rad/s turn-on bias
    n_gyro = sum(1 for _, kind, _ in _messages(0, uwb=False) if kind == 1)
    assert node.fused["imu"] == n_gyro - 150  # 1.5 s at 100 Hz went into the calibration


def test_without_rest_calibration_the_bias_is_learnt_worse_from_the_odometry(runs):
    cfg = load_config(overrides={"ekf.imu_rest_calibration_s": 0.0})
    node = EkfNode(cfg.ekf, wheel_separation_m=cfg.wheel.separation_m, use_imu=True, use_uwb=False)
    for _, kind, msg in _messages(0, uwb=False):
        (node.on_odom, node.on_imu)[kind](msg)
    _, yaw = _errors(node)
    _, yaw_calibrated = _errors(runs["imu"])
    assert abs(node.state[5] - 0.1) < 0.02  # the bias state still converges (the robot stands 2 s)
    assert np.sqrt(np.mean(yaw**2)) > 1.5 * np.sqrt(np.mean(yaw_calibrated**2))


def test_uwb_bounds_the_position_error(runs):
    pos_odom, _ = _errors(runs["odom"])
    assert pos_odom.max() > 0.8  # dead reckoning drifts
    for name in ("uwb", "uwb_imu"):
        pos, _ = _errors(runs[name])
        assert pos.max() < 0.15 and np.sqrt(np.mean(pos**2)) < 0.06, name
        assert runs[name].frame_id == "map"
    assert runs["odom"].frame_id == "odom"


def test_nlos_ranges_are_gated(runs):
    node = runs["uwb"]
    assert 0 < node.rejected_ranges < 0.1 * node.fused["uwb"]


def _converged_uwb_node():
    node = EkfNode(
        CFG.ekf,
        wheel_separation_m=CFG.wheel.separation_m,
        use_imu=False,
        use_uwb=True,
        uwb=CFG.uwb,
        initial_pose=(1.0, 2.0, 0.3),
    )
    for _, kind, msg in _messages(1)[:600]:
        if kind != 1:
            (node.on_odom, None, node.on_range)[kind](msg)
    return node


def test_gating_rejects_an_outlier_and_accepts_a_consistent_range():
    node = _converged_uwb_node()
    x = node.state
    r, _ = node.anchors.model(x, 2)
    stamp = Time.from_sec(node.t_s)
    before = node.rejected_ranges, node.fused["uwb"]
    node.on_range(
        Range(Header(0, stamp, "uwb_anchor_2"), Range.INFRARED, 2 * math.pi, 0.0, 40.0, r + 3.0)
    )
    assert node.rejected_ranges == before[0] + 1 and node.fused["uwb"] == before[1]
    assert np.array_equal(node.state, x)
    node.on_range(
        Range(Header(0, stamp, "uwb_anchor_2"), Range.INFRARED, 2 * math.pi, 0.0, 40.0, r + 0.02)
    )
    assert node.fused["uwb"] == before[1] + 1 and not np.array_equal(node.state, x)


class _FilterpyEkf(ExtendedKalmanFilter):
    """filterpy's EKF as it comes, with only the unicycle prediction of the state (the node's before
    its lean ``predict``/``update``)."""

    dt_s = 0.0

    def predict_x(self, u=0) -> None:
        predict_mean(self.x, self.dt_s)


@pytest.mark.parametrize("seed", [0, 1])
def test_lean_filter_gives_filterpys_bits(seed, monkeypatch):
    msgs = _messages(seed)
    lean = _run(msgs, use_imu=True, use_uwb=True)
    monkeypatch.setattr(ekf_filter, "UnicycleEkf", _FilterpyEkf)
    reference = _run(msgs, use_imu=True, use_uwb=True)
    assert lean.fused == reference.fused and lean.rejected_ranges == reference.rejected_ranges
    assert np.array_equal(lean.history()[1], reference.history()[1])
    assert np.array_equal(lean.filter.P, reference.filter.P)
    assert np.array_equal(
        lean.message(Time.from_sec(1.0)).pose.covariance,
        reference.message(Time.from_sec(1.0)).pose.covariance,
    )


def test_same_seed_same_output():
    a, b, c = (_run(_messages(s)[:3000], use_imu=True, use_uwb=True) for s in (4, 4, 5))
    (ta, pa), (tb, pb), (_, pc) = a.history(), b.history(), c.history()
    assert np.array_equal(ta, tb) and np.array_equal(pa, pb)
    assert not np.array_equal(pa[-10:], pc[-10:])


def test_odometry_poses_differentiated_or_twist():
    """Differential mode follows the odometry's poses (robot_localization's odom0_differential);
    twist mode follows its twists. Here the twists claim twice the speed."""
    results = {}
    for differential in (True, False):
        cfg = load_config(overrides={"ekf.odom_differential": differential})
        node = EkfNode(
            cfg.ekf, wheel_separation_m=cfg.wheel.separation_m, use_imu=False, use_uwb=False
        )
        for k in range(101):
            t = 0.02 * k
            msg = Odometry(
                header=Header(k, Time.from_sec(t), "odom"),
                pose=PoseWithCovariance(
                    Pose(Point(0.5 * t, 0.0, 0.0), Quaternion.from_yaw(0.1 * t))
                ),
                twist=TwistWithCovariance(Twist(Vector3(1.0, 0, 0), Vector3(0, 0, 0.2))),
            )
            node.on_odom(msg)
        results[differential] = node.state
    assert results[True][3] == pytest.approx(0.5, abs=0.01) and results[True][4] == pytest.approx(
        0.1, abs=0.01
    )
    assert results[True][2] == pytest.approx(0.2, abs=0.01)
    assert results[False][3] == pytest.approx(1.0, abs=0.01) and results[False][4] == pytest.approx(
        0.2, abs=0.01
    )


def test_bus_node_publishes_filtered_odometry():
    clock = VirtualClock()
    bus = Bus(clock)
    out = []
    bus.subscribe("odometry/filtered", out.append)
    node = EkfNode(
        CFG.ekf,
        wheel_separation_m=CFG.wheel.separation_m,
        use_imu=True,
        use_uwb=False,
        bus=bus,
        initial_pose=(1.0, 0.0, 0.0),
    )
    for k in range(10):
        stamp = Time.from_us(k * 20_000)
        bus.publish(
            "imu/data_raw",
            Imu(header=Header(k, stamp, "imu_link"), angular_velocity=Vector3(0, 0, 0.05)),
        )
        bus.publish(
            "odom",
            Odometry(
                header=Header(k, stamp, "odom"),
                twist=TwistWithCovariance(Twist(Vector3(0.0, 0, 0), Vector3(0, 0, 0))),
            ),
        )
    assert (
        len(out) == node.fused["odom"] == (10 if not CFG.ekf.odom_differential else 9)
    )  # (a first pose
    # only primes a differentiation)
    msg = out[-1]
    assert msg.header.frame_id == "odom" and msg.child_frame_id == "base_link"
    assert msg.pose.pose.position.x == pytest.approx(1.0, abs=1e-3)
    assert msg.header.stamp == Time.from_us(180_000)
    cov = msg.pose.covariance.reshape(6, 6)
    assert cov[0, 0] > 0 and cov[5, 5] > 0 and cov[2, 2] == 0.0


def test_bad_arguments_name_the_field():
    with pytest.raises(ValueError, match="anchors_xy_m"):
        EkfNode(CFG.ekf, wheel_separation_m=CFG.wheel.separation_m, use_imu=False, use_uwb=True)
    with pytest.raises(ValueError, match="initial_pose"):
        EkfNode(
            CFG.ekf,
            wheel_separation_m=CFG.wheel.separation_m,
            use_imu=False,
            use_uwb=False,
            initial_pose=(0.0, 1.0),
        )
    with pytest.raises(ValueError, match="use_odom"):
        EkfNode(
            CFG.ekf,
            wheel_separation_m=CFG.wheel.separation_m,
            use_odom=False,
            use_imu=False,
            use_uwb=False,
        )
    node = EkfNode(
        CFG.ekf, wheel_separation_m=CFG.wheel.separation_m, use_imu=False, use_uwb=True, uwb=CFG.uwb
    )
    with pytest.raises(ValueError, match="header.frame_id"):
        node.on_range(Range(Header(0, Time(), "uwb_anchor_9"), Range.INFRARED, 1.0, 0.0, 40.0, 3.0))


def _pose_msg(x, y, yaw, cov_xy_yaw, t_s, frame="map"):
    from amr_twin.ros.geometry_messages import PoseWithCovarianceStamped

    cov = np.diag([1.0, 1.0, 1e6, 1e6, 1e6, 1.0])
    cov[np.ix_([0, 1, 5], [0, 1, 5])] = np.diag(cov_xy_yaw)
    return PoseWithCovarianceStamped(
        Header(0, Time.from_sec(t_s), frame),
        PoseWithCovariance(Pose(Point(x, y, 0.0), Quaternion.from_yaw(yaw)), cov.ravel()),
    )


def _map_ekf(initial_pose):
    """An EKF in ``map`` (UWB on) on a bus, and the list its ``odometry/filtered`` messages go
    to."""
    bus = Bus(VirtualClock())
    out = []
    bus.subscribe("odometry/filtered", out.append)
    node = EkfNode(
        CFG.ekf,
        wheel_separation_m=CFG.wheel.separation_m,
        use_imu=False,
        use_uwb=True,
        uwb=CFG.uwb,
        bus=bus,
        initial_pose=initial_pose,
    )
    return bus, node, out


def test_a_matched_pose_is_fused_by_its_own_covariance():
    """The map match's pose (AMCL's amcl_pose as robot_localization's pose0): a tight one pulls the
    state onto it, a direction its covariance leaves open (an aisle's length) is left to the rest;
    the yaw across +-pi moves the short way; the node publishes after it; a pose not in ``map`` is
    refused."""
    bus, node, out = _map_ekf((2.0, 3.0, 3.1))
    bus.publish("map_match/pose", _pose_msg(2.5, 3.4, -3.1, (1e4, 0.03**2, 0.01**2), 0.0))
    x, y, yaw = node.state[:3]
    p0, q0 = (
        CFG.ekf.initial_xy_sigma_m**2,
        CFG.ekf.initial_yaw_sigma_rad**2,
    )  # the prior's variances
    assert (
        x == pytest.approx(2.0 + 0.5 * p0 / (p0 + 1e4), abs=1e-6) and x - 2.0 < 1e-3
    )  # x: open, unmoved
    assert (
        y == pytest.approx(3.0 + 0.4 * p0 / (p0 + 0.03**2), abs=1e-6) and y > 3.2
    )  # y: tight, taken in
    short_way = 2 * math.pi - 6.2  # -3.1 is 0.083 rad past 3.1
    assert math.remainder(yaw - (3.1 + short_way * q0 / (q0 + 0.01**2)), math.tau) == pytest.approx(
        0, abs=1e-6
    )
    assert (
        node.fused["pose"] == 1
        and len(out) == 1
        and out[0].pose.pose.position.y == pytest.approx(y)
    )
    with pytest.raises(ValueError, match="frame_id"):
        node.on_pose(_pose_msg(2.5, 3.4, 0.0, (0.01, 0.01, 0.01), 0.1, frame="odom"))


def test_a_pose_of_an_earlier_instant_is_carried_to_the_filters_time():
    """The navigator matches the pose it was given, which the filter has since moved on from
    (odometry at 50 Hz, the match 0.1 s later): a pose equal to the filter's own of that instant
    must not move it (fused as if current, it would pull the robot back by 0.08 m at 0.8 m/s, each
    match: the estimate lagged 1.5 m behind along a 40 m aisle); the published pose is the corrected
    one of that instant, at its stamp."""
    bus, node, out = _map_ekf((2.0, 3.0, 0.5))
    for k in range(60):
        x = 2.0 + 0.8 * 0.02 * k
        bus.publish(
            "odom",
            Odometry(
                header=Header(k, Time.from_us(k * 20_000), "odom"),
                pose=PoseWithCovariance(Pose(Point(x, 0.0, 0.0), Quaternion.from_yaw(0.0))),
                twist=TwistWithCovariance(Twist(Vector3(0.8, 0, 0), Vector3(0, 0, 0))),
            ),
        )
    then_msg = out[-6]  # 0.1 s before the filter's time
    then = np.array(
        [
            then_msg.pose.pose.position.x,
            then_msg.pose.pose.position.y,
            then_msg.pose.pose.orientation.yaw_rad(),
        ]
    )
    now = node.state[:3]
    assert np.hypot(*(now[:2] - then[:2])) > 0.07
    bus.publish(
        "map_match/pose",
        _pose_msg(*then, (0.01**2, 0.01**2, 0.005**2), then_msg.header.stamp.to_sec()),
    )
    assert node.state[:3] == pytest.approx(now, abs=1e-6)
    assert out[-1].header.stamp == then_msg.header.stamp
    assert out[-1].pose.pose.position.x == pytest.approx(then[0], abs=1e-6)
    shifted = then + [0.0, 0.05, 0.0]  # 5 cm further in map y then: so now
    bus.publish(
        "map_match/pose",
        _pose_msg(*shifted, (0.01**2, 0.01**2, 0.005**2), then_msg.header.stamp.to_sec()),
    )
    moved = node.state[:3] - now
    assert abs(moved[0]) < 1e-3 and 0.02 < moved[1] < 0.05 and abs(moved[2]) < 1e-3, moved
