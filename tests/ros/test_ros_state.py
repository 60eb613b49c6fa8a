"""A recording is a bag ROS 2 tools accept, checked with rosbags (and yourdfpy) only.

The run of the issue, ``amr-twin run linear --speed-m-s 0.5 --duration-s 8 --sensors --mcap r.mcap
--world empty``, read back with rosbags' rosbag2 Reader and its ROS 2 Humble deserializer:
continuous odometry whose twist integrates to its pose, one tf tree per REP-105 root, joint
states of every moving joint of the URDF in the bag, ``/clock``, sensor stamps covered by
tf, a ground truth that moves, the UWB frames, ``/cmd_vel`` and the service calls.
"""

import collections
import io
import math

import numpy as np
import pytest
from typer.testing import CliRunner

from amr_twin.analysis.se2 import yaw_of_quaternion
from amr_twin.cli.main import app
from amr_twin.estimation.dead_reckoning import twist_step

from uwb_run import record_uwb_run

RUN_S = 8.0


def _read(path):
    """topic -> [(log time ns, message)] decoded by rosbags with ROS 2 Humble's definitions."""
    from rosbags.rosbag2 import Reader
    from rosbags.typesys import Stores, get_typestore

    humble = get_typestore(Stores.ROS2_HUMBLE)
    out = collections.defaultdict(list)
    with Reader(path) as reader:
        for con, t_ns, data in reader.messages():
            out[con.topic].append((t_ns, humble.deserialize_cdr(data, con.msgtype)))
    return out


def _t(stamp) -> float:
    return stamp.sec + stamp.nanosec * 1e-9


def _yaw(q) -> float:
    return yaw_of_quaternion(q.w, q.x, q.y, q.z)


@pytest.fixture(scope="module")
def issue_bag(tmp_path_factory):
    path = tmp_path_factory.mktemp("issue13") / "r.mcap"
    res = CliRunner().invoke(
        app,
        [
            "run",
            "linear",
            "--speed-m-s",
            "0.5",
            "--duration-s",
            str(RUN_S),
            "--sensors",
            "--mcap",
            str(path),
            "--world",
            "empty",
            "--json",
        ],
    )
    assert res.exit_code == 0, res.output
    return _read(path)


def _odom(bag) -> np.ndarray:
    """(n, 7): stamp s, x, y, yaw, vx, vy, w of /odom."""
    return np.array(
        [
            (
                _t(m.header.stamp),
                m.pose.pose.position.x,
                m.pose.pose.position.y,
                _yaw(m.pose.pose.orientation),
                m.twist.twist.linear.x,
                m.twist.twist.linear.y,
                m.twist.twist.angular.z,
            )
            for _t_ns, m in bag["/odom"]
        ]
    )


def _truth(bag) -> np.ndarray:
    """(n, 6): stamp s, x, y, yaw, twist vx, wz of /twin/ground_truth."""
    return np.array(
        [
            (
                _t(m.header.stamp),
                m.pose.pose.position.x,
                m.pose.pose.position.y,
                _yaw(m.pose.pose.orientation),
                m.twist.twist.linear.x,
                m.twist.twist.angular.z,
            )
            for _t_ns, m in bag["/twin/ground_truth"]
        ]
    )


def test_odometry_steps_no_more_than_the_true_motion_allows(issue_bag):
    """Between consecutive /odom messages: |dp| <= |v| dt + 1 cm, |dyaw| <= |w| dt + 0.01 rad (v, w
    true)."""
    o, g = _odom(issue_bag), _truth(issue_bag)
    assert len(o) == 50 * RUN_S + 1 and np.allclose(np.diff(o[:, 0]), 0.02)
    g_yaw = np.unwrap(g[:, 3])
    worst_m = worst_rad = -1.0
    for k in range(1, len(o)):
        t0, t1 = o[k - 1, 0], o[k, 0]
        sel = (g[:, 0] >= t0 - 1e-9) & (g[:, 0] <= t1 + 1e-9)
        true_path_m = np.hypot(np.diff(g[sel, 1]), np.diff(g[sel, 2])).sum()
        true_turn_rad = np.abs(np.diff(g_yaw[sel])).sum()
        step_m = math.hypot(o[k, 1] - o[k - 1, 1], o[k, 2] - o[k - 1, 2])
        step_rad = abs(math.remainder(o[k, 3] - o[k - 1, 3], 2 * math.pi))
        worst_m = max(worst_m, step_m - true_path_m)
        worst_rad = max(worst_rad, step_rad - true_turn_rad)
    assert worst_m <= 0.01 and worst_rad <= 0.01
    assert np.hypot(o[-1, 1], o[-1, 2]) > 3.5  # and it did follow the drive (about 4 m)


def test_odometry_twist_integrates_to_its_pose(issue_bag):
    o = _odom(issue_bag)
    pose = tuple(o[0, 1:4])
    for k in range(1, len(o)):  # the twist in force over each period is the one stamped at its end
        pose = twist_step(pose, o[k, 4], o[k, 5], o[k, 6], o[k, 0] - o[k - 1, 0])
    final = o[-1, 1:3]
    assert np.linalg.norm(np.array(pose[:2]) - final) <= 0.02 * np.linalg.norm(final)
    assert abs(math.remainder(pose[2] - o[-1, 3], 2 * math.pi)) <= 0.02


def _parents(bag) -> dict[str, set[str]]:
    parents = collections.defaultdict(set)
    for topic in ("/tf", "/tf_static"):
        for _t_ns, m in bag[topic]:
            for tr in m.transforms:
                parents[tr.child_frame_id].add(tr.header.frame_id)
    return parents


def test_tf_frames_have_one_parent_and_odom_none(issue_bag):
    parents = _parents(issue_bag)
    assert all(len(p) == 1 for p in parents.values()), parents
    assert (
        "odom" not in parents
        and "world" not in parents
        and "world" not in set().union(*parents.values())
    )
    parent = {child: next(iter(p)) for child, p in parents.items()}

    def root(frame):
        while frame in parent:
            frame = parent[frame]
        return frame

    expected = {
        "base_link",
        "laser",
        "imu_link",
        "uwb_tag",
        "wheel_left_link",
        "wheel_right_link",
        "caster_front_left_link",
        "caster_front_right_link",
        "caster_rear_left_link",
        "caster_rear_right_link",
    }
    assert set(parent) == expected and parent["base_link"] == "odom"
    assert {root(f) for f in parent} == {"odom"}
    assert all(parent[f] == "base_link" for f in expected - {"base_link"})


def test_joint_states_name_every_moving_joint_of_the_bag_urdf_and_clock_runs(issue_bag):
    import yourdfpy

    urdf = issue_bag["/robot_description"][0][1].data
    robot = yourdfpy.URDF.load(io.StringIO(urdf), load_meshes=False, build_scene_graph=False)
    moving = {j.name for j in robot.robot.joints if j.type != "fixed"}
    states = [m for _t_ns, m in issue_bag["/joint_states"]]
    assert len(moving) == 6 and all(
        set(m.name) == moving and len(m.position) == len(m.velocity) == 6 for m in states
    )
    # the wheels roll forward at the commanded 38.2 RPM at the end, within the faithful PI's 4 RPM
    # dead zone (listing 4.11: the calibrated plant ends at 41.7 on 9 duty counts); the casters sit
    # within their stroke
    last = dict(zip(states[-1].name, states[-1].velocity))
    assert last["wheel_left_joint"] * 60 / (2 * math.pi) == pytest.approx(38.2, abs=4.0)
    travel = max(float(j.limit.upper) for j in robot.robot.joints if j.type == "prismatic")
    assert all(
        -1e-3 <= p <= travel + 1e-3
        for m in states
        for n, p in zip(m.name, m.position)
        if "caster" in n
    )
    # every link a joint moves is placed by /tf at the joint state's stamps
    tf_stamps = {
        _t(tr.header.stamp)
        for _t_ns, m in issue_bag["/tf"]
        for tr in m.transforms
        if tr.child_frame_id == "wheel_left_link"
    }
    assert {_t(m.header.stamp) for m in states} <= tf_stamps
    clock = [_t(m.clock) for _t_ns, m in issue_bag["/clock"]]
    assert clock[0] == 0.0 and clock[-1] == pytest.approx(RUN_S) and np.all(np.diff(clock) > 0)


def test_no_sensor_stamp_before_the_first_odom_transform_and_all_covered(issue_bag):
    base_tf = [
        _t(tr.header.stamp)
        for _t_ns, m in issue_bag["/tf"]
        for tr in m.transforms
        if tr.child_frame_id == "base_link"
    ]
    first, last = min(base_tf), max(base_tf)
    scans = [m for _t_ns, m in issue_bag["/scan"]]
    imu = [_t(m.header.stamp) for _t_ns, m in issue_bag["/imu/data_raw"]]
    assert len(scans) > 30 and len(imu) > 700
    beams = np.concatenate(
        [_t(m.header.stamp) + m.time_increment * np.arange(len(m.ranges)) for m in scans]
    )
    assert first <= beams.min() and beams.max() <= last
    assert first <= min(imu) and max(imu) <= last
    for topic in ("/scan", "/imu/data_raw", "/odom", "/joint_states", "/twin/ground_truth"):
        stamps = [_t(m.header.stamp) for _t_ns, m in issue_bag[topic]]
        assert np.all(np.diff(stamps) > 0), topic


def test_laser_scan_is_counter_clockwise_and_timed_clockwise(issue_bag):
    scan = issue_bag["/scan"][3][1]
    assert scan.angle_increment > 0 and scan.time_increment < 0  # CCW array, the A1 spins clockwise
    assert (len(scan.ranges) - 1) * -scan.time_increment == pytest.approx(scan.scan_time, rel=0.01)


def test_ground_truth_twist_is_the_true_motion(issue_bag):
    g = _truth(issue_bag)
    dt = np.diff(g[:, 0])
    c, s = np.cos(g[:-1, 3]), np.sin(g[:-1, 3])
    v_fd = (c * np.diff(g[:, 1]) + s * np.diff(g[:, 2])) / dt  # forward speed by finite differences
    moving = g[:-1, 0] > 4.0
    assert np.median(g[1:, 4][moving]) == pytest.approx(
        0.5, abs=0.055
    )  # 4 RPM of wheel speed: 0.052 m/s
    assert np.allclose(0.5 * (g[:-1, 4] + g[1:, 4])[moving], v_fd[moving], atol=0.01)
    assert issue_bag["/twin/ground_truth"][0][1].header.frame_id == "world"


@pytest.fixture(scope="module")
def uwb_bag(tmp_path_factory):
    cfg, _capture, paths = record_uwb_run(tmp_path_factory.mktemp("uwb13"), rrd=False)
    return cfg, _read(paths["mcap"])


def test_uwb_frames_exist_in_tf_static_on_the_map_side(uwb_bag):
    cfg, bag = uwb_bag
    static = {tr.child_frame_id: tr for tr in bag["/tf_static"][0][1].transforms}
    for i, (x, y) in enumerate(cfg.uwb.anchors_xy_m):
        tr = static[f"uwb_anchor_{i}"]
        assert tr.header.frame_id == "map"
        v = tr.transform.translation
        assert (v.x, v.y, v.z) == pytest.approx((x, y, cfg.uwb.anchor_z_m))
    tag = static["uwb_tag"]
    assert tag.header.frame_id == "base_link"
    v = tag.transform.translation
    assert (v.x, v.y, v.z) == pytest.approx(cfg.uwb.tag_pos_m)
    frames = {m.header.frame_id for _t_ns, m in bag["/uwb/range"]}
    assert frames and frames <= set(static)
    parents = _parents(bag)
    assert all(len(p) == 1 for p in parents.values()) and "odom" not in parents


def test_cmd_vel_and_service_calls_are_in_the_bag(tmp_path):
    from amr_twin.model.config import load_config
    from amr_twin.controllers.diff_drive import DiffDriveNode
    from amr_twin.assembly.twin import Twin, TwinOptions
    from amr_twin.ros.geometry_messages import Twist, Vector3
    from amr_twin.recording.rerun_capture import attach
    from amr_twin.recording.rerun_log import record_run

    twin = Twin(load_config(), TwinOptions(world="empty", firmware="improved"))
    attach(twin)
    DiffDriveNode(twin.bus, twin.clock, client=twin.client, cmd_timeout_s=0.5)
    twin.advance(0.1)
    twin.bus.publish("cmd_vel", Twist(Vector3(0.4, 0.0, 0.0), Vector3(0.0, 0.0, 0.5)))
    twin.advance(1.0)  # the command times out: a stop call follows
    bag = _read(record_run(twin, mcap_path=tmp_path / "c.mcap")["mcap"])
    ((t_ns, cmd),) = bag["/cmd_vel"]
    assert t_ns == 100_000_000 and (cmd.linear.x, cmd.angular.z) == (0.4, 0.5)
    calls = [m.data.tolist() for _t_ns, m in bag["/wheel_Command_Service/request"]]
    left, right = (
        (0.4 - 0.5 * 0.24) * 60 / (math.pi * 0.25),
        (0.4 + 0.5 * 0.24) * 60 / (math.pi * 0.25),
    )
    assert len(calls) == 2 and calls[0] == pytest.approx([1, left, 1, right], rel=1e-6)
    assert calls[1] == [0.0, 0.0, 0.0, 0.0]
    assert [m.data.tolist() for _t_ns, m in bag["/wheel_Command"]] == calls


def test_the_state_samplers_c_form_keeps_the_python_forms_values_and_arrays_take_a_period():
    from amr_twin.model.config import load_config
    from amr_twin.ros.ros_state import StateSampler
    from amr_twin.assembly.twin import Twin, TwinOptions

    twin = Twin(load_config(), TwinOptions(world="empty"))
    native = StateSampler(twin.observables.model, twin.observables.named)
    python = StateSampler(twin.observables.model, twin.observables.named, native=False)
    assert native.sample.grid_native is not None and python.sample.grid_native is None
    twin.samplers += [native.sample, python.sample]
    twin.client.linear(0.5)
    twin.advance(
        0.5
    )  # the loop's grid in Python (a sampler without a C form): both samplers called there
    twin.samplers.remove(python.sample)
    twin.advance(0.5)  # in C: the native one alone
    assert len(native) == 100 and np.array_equal(native.sample.rows[:50], python.sample.rows)
    assert native.t_us == list(range(10_000, 1_000_001, 10_000))
    moved = native.arrays()
    assert (
        np.ptp(moved["pos"][:, 0]) > 0.1 and np.ptp(moved["q"][:, 0]) > 1.0
    )  # the robot drove, its wheels turned
    half = native.split(500_000)
    assert (
        half.t_us[-1] == 500_000 and native.t_us[0] == 510_000
    )  # split takes the samples up to the instant
    every = half.arrays(20_000, base=False)
    full = half.arrays()
    assert every["t_us"].tolist() == list(range(20_000, 500_001, 20_000)) and "pos" not in every
    for key in ("q", "qd", "link_pos", "link_quat"):
        assert np.array_equal(every[key], full[key][1::2]), key
