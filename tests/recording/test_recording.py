""".rrd (Rerun) and .mcap (ROS 2) recordings, read back with the formats' own readers."""

import collections
import json

import numpy as np
import pytest
from typer.testing import CliRunner

from amr_twin.cli.main import app
from amr_twin.model.actor_paths import actor_path
from amr_twin.model.actors import Actor
from amr_twin.model.config import load_config
from amr_twin.assembly.twin import Twin, TwinOptions
from amr_twin.recording.rerun_capture import attach
from amr_twin.recording.rerun_log import record_run
from amr_twin.assembly.command import Command
from amr_twin.recording.run import run_mission
from amr_twin.recording.recorder import attach_recorder, recorder_of

from uwb_run import UWB_S, record_uwb_run

DURATION_S = 4.0
STEPS = [
    (0.0, Command("linear", speed_m_s=0.5)),
    (2.0, Command("angular", speed_deg_s=30.0, icc_m=0.0)),
]
WALKER = Actor("person", ((3.0, -2.0), (3.0, 2.0)), 1.2, loop=True)


@pytest.fixture(scope="module")
def recorded(tmp_path_factory):
    cfg = load_config()
    options = TwinOptions(sensors=("imu", "lidar"), actors=(WALKER,))
    twin = Twin(cfg, options)
    attach_recorder(twin)
    capture = attach(twin)
    result = run_mission(cfg, STEPS, DURATION_S, options, twin=twin)
    out = tmp_path_factory.mktemp("rec")
    paths = record_run(twin, rrd_path=out / "run.rrd", mcap_path=out / "run.mcap", result=result)
    plain = run_mission(cfg, STEPS, DURATION_S, options)
    return cfg, capture, result, plain, paths


def _rrd_chunks(path):
    from rerun.chunk import RrdReader

    rows = collections.Counter()
    batches = collections.defaultdict(list)
    for chunk in RrdReader(str(path)).stream().to_chunks():
        rows[str(chunk.entity_path)] += chunk.num_rows
        batches[str(chunk.entity_path)].append(chunk.to_record_batch())
    return rows, batches


def _mcap_messages(path):
    from mcap.reader import make_reader
    from mcap_ros2.decoder import DecoderFactory

    out = collections.defaultdict(list)
    with open(path, "rb") as f:
        reader = make_reader(f, decoder_factories=[DecoderFactory()])
        for schema, channel, message, decoded in reader.iter_decoded_messages():
            out[channel.topic].append(
                (message.log_time, schema.name, schema.encoding, channel.message_encoding, decoded)
            )
    return out


def test_recording_does_not_change_the_run(recorded):
    _cfg, _capture, result, plain, _paths = recorded
    assert np.array_equal(result.series.true_rpm, plain.series.true_rpm)
    assert np.array_equal(result.series.odom, plain.series.odom)
    assert np.array_equal(result.series.pose, plain.series.pose)


def test_files_written_atomically(recorded):
    paths = recorded[4]
    for path in paths.values():
        assert path.exists() and path.stat().st_size > 10_000
        assert not list(path.parent.glob(".*.tmp"))


def test_rrd_entities_and_rates(recorded):
    _cfg, capture, result, _plain, paths = recorded
    rows, batches = _rrd_chunks(paths["rrd"])
    entities = set(rows)
    for entity in (
        "/world/bodies/amr/base_link",
        "/world/bodies/amr/wheel_left_link",
        "/world/bodies/amr/caster_rear_right_link",
        "/world/bodies/world/geoms/boxes",
        "/world/bodies/amr/base_link/geoms/boxes",
        "/world/bodies/amr/wheel_left_link/geoms/cylinders",
        "/world/scan",
        "/world/bodies/amr/laser/scan",
        "/world/trajectory/true/0000",
        "/world/trajectory/odom/0000",
        "/wheels/left/true_rpm",
        "/wheels/right/published_rpm",
        "/wheels/left/reference_rpm",
        "/duty/left",
        "/imu/accel",
        "/imu/gyro",
        "/commands",
        "/electrics/left/current_a",
        "/electrics/battery/current_a",
        "/electrics/battery/voltage_v",
    ):
        assert entity in entities, entity
    assert rows["/electrics/right/current_a"] == len(result.series.t_s)
    # body transforms at ~30 Hz (33.3 Hz on the 10 ms grid) over the run
    n_tf = rows["/world/bodies/amr/wheel_left_link"]
    assert abs(n_tf - DURATION_S * 1e6 / capture.period_us) <= 2
    assert rows["/wheels/left/true_rpm"] == len(result.series.t_s)
    n_scans = len(capture.messages["scan"])
    assert abs(n_scans - DURATION_S * 5.5) <= 2
    assert rows["/world/scan"] == n_scans
    assert rows["/commands"] == len(STEPS) * 2  # client call + wheel_Command
    # the default blueprint travels in the file
    from rerun.chunk import RrdReader

    reader = RrdReader(str(paths["rrd"]))
    assert len(reader.recordings()) == 1 and len(reader.blueprints()) == 1
    views = {str(c.entity_path) for c in reader.stream(store=reader.blueprints()[0]).to_chunks()}
    assert (
        sum(v.startswith("/view/") and v.count("/") == 2 for v in views) >= 5
    )  # 3D, text, 3-4 plots
    # one value back: the last true RPM of the left wheel
    last = batches["/wheels/left/true_rpm"][-1]
    values = last.column("Scalars:scalars").to_pylist()
    assert values[-1][0] == pytest.approx(result.series.true_rpm[-1, 0])
    # the wheel turns: its transform's rotation changes over the run
    quats = np.concatenate(
        [
            np.array(b.column("Transform3D:quaternion").to_pylist(), dtype=object).ravel()
            for b in batches["/world/bodies/amr/wheel_left_link"]
        ]
    )
    assert len({tuple(np.round(np.ravel(q), 3)) for q in quats}) > 10
    assert not any(
        e.startswith(("/uwb", "/world/uwb")) for e in entities
    )  # no UWB sensor: no UWB ranges


def test_rrd_actor_body_walks_its_path_with_its_geoms(recorded):
    """The walker's body in the .rrd: its legs, torso and head, and its transform at ~30 Hz where
    its path puts it (one grid instant, 10 ms, behind: MuJoCo moves a mocap body at the next
    step)."""
    cfg, capture, _result, _plain, paths = recorded
    rows, batches = _rrd_chunks(paths["rrd"])
    assert (
        "/world/bodies/person_0/geoms/cylinders" in rows
        and "/world/bodies/person_0/geoms/boxes" in rows
    )
    t = (
        np.concatenate(
            [
                b.column("sim_time").to_numpy()
                for b in batches["/world/bodies/person_0"]
                if "sim_time" in b.schema.names
            ]
        )
        .astype("timedelta64[ns]")
        .astype(float)
        * 1e-9
    )
    xyz = np.concatenate(
        [
            np.array(b.column("Transform3D:translation").to_pylist(), dtype=float).reshape(-1, 3)
            for b in batches["/world/bodies/person_0"]
            if "sim_time" in b.schema.names
        ]
    )
    path = actor_path(WALKER, cfg)
    want = np.array([path.pose_at(max(0.0, s - 0.01))[:2] for s in t])
    assert (
        len(t) >= DURATION_S * 30 - 2 and np.abs(xyz[:, :2] - want).max() < 1e-6
    )  # float32 in the file
    assert np.ptp(xyz[:, 1]) > 3.0  # it walked


def test_rrd_scans_are_the_scans_beams(recorded):
    """Each scan row holds its own beams with a return: in the laser frame at their measured
    ranges and angles, in the world at the same distance from the laser's track, stamped at
    the end of the rotation."""
    from amr_twin.sensors.lidar_beams import scan_end_time_s

    _cfg, capture, _result, _plain, paths = recorded
    _rows, batches = _rrd_chunks(paths["rrd"])

    def column(entity, name):
        return [v for b in batches[entity] for v in b.column(name).to_pylist()]

    scans = [msg for _t, msg in capture.messages["scan"]]
    local = column("/world/bodies/amr/laser/scan", "Points3D:positions")
    world = column("/world/scan", "Points3D:positions")
    times = column("/world/scan", "sim_time")
    assert len(local) == len(world) == len(times) == len(scans) > 10
    for k in (0, len(scans) // 2, len(scans) - 1):
        msg, pts, wpts = scans[k], np.array(local[k]), np.array(world[k])
        ok = np.isfinite(msg.ranges)
        angles = (msg.angle_min + msg.angle_increment * np.arange(len(msg.ranges)))[ok]
        assert len(pts) == len(wpts) == ok.sum() > 100
        np.testing.assert_allclose(np.hypot(pts[:, 0], pts[:, 1]), msg.ranges[ok], rtol=1e-5)
        np.testing.assert_allclose(
            np.arctan2(pts[:, 1], pts[:, 0]), np.angle(np.exp(1j * angles)), atol=1e-5
        )
        laser_z = wpts[0, 2]
        assert (
            np.allclose(wpts[:, 2], laser_z, atol=1e-3) and 0.1 < laser_z < 1.0
        )  # the chassis pitches a little
        assert abs(times[k].total_seconds() - scan_end_time_s(msg)) < 1e-6


def test_mcap_topics_rates_and_values(recorded):
    _cfg, capture, result, _plain, paths = recorded
    msgs = _mcap_messages(paths["mcap"])
    expect = {
        "/odom": "nav_msgs/msg/Odometry",
        "/tf": "tf2_msgs/msg/TFMessage",
        "/tf_static": "tf2_msgs/msg/TFMessage",
        "/scan": "sensor_msgs/msg/LaserScan",
        "/imu/data_raw": "sensor_msgs/msg/Imu",
        "/imu/mag": "sensor_msgs/msg/MagneticField",
        "/wheel_Command": "std_msgs/msg/Float64MultiArray",
        "/wheel0_Vel": "std_msgs/msg/Float64",
        "/twin/true_rpm": "std_msgs/msg/Float64MultiArray",
        "/twin/ground_truth": "nav_msgs/msg/Odometry",
    }
    for topic, schema in expect.items():
        assert topic in msgs, topic
        assert {(m[1], m[2], m[3]) for m in msgs[topic]} == {(schema, "ros2msg", "cdr")}
    # rates: odom and tf at 50 Hz, IMU at its configured rate, scans at 5.5 Hz
    assert abs(len(msgs["/odom"]) - 50 * DURATION_S) <= 2
    assert (
        abs(len(msgs["/tf"]) - 2 * 50 * DURATION_S) <= 4
    )  # odom -> base_link and the joints' links
    cfg = recorded[0]
    assert abs(len(msgs["/imu/data_raw"]) - cfg.imu.rate_hz * DURATION_S) <= 2
    assert abs(len(msgs["/scan"]) - cfg.lidar.scan_rate_hz * DURATION_S) <= 2
    assert len(msgs["/twin/true_rpm"]) == len(result.series.t_s)
    assert len(msgs["/wheel_Command"]) == len(STEPS)
    # log times in order, in simulation time
    times = [m[0] for topic in msgs for m in msgs[topic]]
    assert max(times) <= DURATION_S * 1e9
    # values against the simulation
    odom = msgs["/odom"][-1][4]
    assert odom.header.frame_id == "odom" and odom.child_frame_id == "base_link"
    assert odom.pose.pose.position.x == pytest.approx(result.series.odom[-1, 1], abs=1e-12)
    assert odom.pose.pose.position.y == pytest.approx(result.series.odom[-1, 2], abs=1e-12)
    scan = msgs["/scan"][-1][4]
    src = capture.messages["scan"][-1][1]
    assert np.allclose(
        np.asarray(scan.ranges, np.float32), np.asarray(src.ranges, np.float32), equal_nan=True
    )
    imu, imu_src = msgs["/imu/data_raw"][-1][4], capture.messages["imu/data_raw"][-1][1]
    assert imu.linear_acceleration.z == imu_src.linear_acceleration.z
    assert imu.angular_velocity.z == imu_src.angular_velocity.z
    assert list(imu.orientation_covariance) == list(imu_src.orientation_covariance)
    truth = msgs["/twin/ground_truth"][-1][4]
    assert truth.pose.pose.position.x == pytest.approx(result.series.pose[-1, 0])
    assert list(msgs["/wheel_Command"][0][4].data) == pytest.approx(result.series.commands[0][1])
    frames = {t.child_frame_id for t in msgs["/tf_static"][0][4].transforms}
    assert frames == {"laser", "imu_link", "uwb_tag"}


def test_cli_record_and_mcap(tmp_path):
    rrd, mcap = tmp_path / "cli.rrd", tmp_path / "cli.mcap"
    res = CliRunner().invoke(
        app,
        [
            "run",
            "linear",
            "--speed-m-s",
            "0.5",
            "--duration-s",
            "1",
            "--record",
            str(rrd),
            "--mcap",
            str(mcap),
            "--json",
        ],
    )
    assert res.exit_code == 0, res.output
    info = json.loads(res.stdout)
    msgs = _mcap_messages(mcap)
    assert abs(len(msgs["/odom"]) - 50) <= 1
    assert msgs["/odom"][-1][4].pose.pose.position.x == pytest.approx(
        info["final_odom_pose"]["x_m"]
    )
    rows, _ = _rrd_chunks(rrd)
    assert "/world/bodies/amr/base_link" in rows and "/wheels/right/true_rpm" in rows
    assert (
        "/world/bodies/amr/base_link/geoms/boxes" in rows
    )  # a recording run keeps the robot's visuals


def test_recording_does_not_change_a_run_advanced_in_small_steps():
    """The capture samples on the loop's grid, not by clock events: a 20 ms advance loop is
    unchanged too."""
    cfg = load_config()

    def drive(record: bool):
        twin = Twin(cfg, TwinOptions(world="empty"))
        attach_recorder(twin)
        capture = attach(twin) if record else None
        twin.advance_to_us(0)
        Command("linear", speed_m_s=0.7).send(twin)
        for k in range(1, 51):
            twin.advance_to_us(k * 20_000)
        return recorder_of(twin).series(), capture

    plain, _ = drive(False)
    recorded, capture = drive(True)
    assert np.array_equal(plain.true_rpm, recorded.true_rpm) and np.array_equal(
        plain.pose, recorded.pose
    )
    t_s, pos, _quat = capture.body_poses()
    assert np.allclose(np.diff(t_s), capture.period_us / 1e6) and t_s[-1] > 0.95
    base = int(
        np.nonzero(capture.body_ids == capture.twin.physics.model.body("amr/base_link").id)[0][0]
    )
    assert pos[-1, base, 0] > pos[0, base, 0] + 0.1  # the robot drove forward


def test_stale_temporaries_of_dead_writers_are_removed(tmp_path):
    import os
    import subprocess

    from amr_twin.recording.rerun_capture import recording_folder, remove_stale_temporaries

    dead = subprocess.Popen(["true"])
    dead.wait()
    stale = [tmp_path / f".run1.rrd.{dead.pid}.tmp", tmp_path / f".p.mcap.{dead.pid}.tmp"]
    keep = [
        tmp_path / f".run2.rrd.{os.getpid()}.tmp",  # a live writer's
        tmp_path / ".sweep.csv.abc123.tmp",  # not a recording
        tmp_path / "run3.rrd",
    ]
    for path in stale + keep:
        path.write_bytes(b"x")
    assert sorted(remove_stale_temporaries(tmp_path)) == sorted(stale)
    assert sorted(tmp_path.iterdir()) == sorted(keep)
    assert recording_folder(tmp_path / "new" / "rec") == (tmp_path / "new" / "rec").resolve()
    assert (tmp_path / "new" / "rec").is_dir()


@pytest.fixture(scope="module")
def uwb_recorded(tmp_path_factory):
    """A 2 s run with the UWB tag (no IMU/LiDAR), recorded to .rrd and .mcap."""
    return record_uwb_run(tmp_path_factory.mktemp("uwb"))


def test_rrd_uwb_ranges_per_anchor(uwb_recorded):
    from amr_twin.recording.rerun_uwb import uwb_ranges

    cfg, capture, paths = uwb_recorded
    msgs = capture.messages["uwb/range"]
    n_anchors = len(cfg.uwb.anchors_x_m)
    assert (
        0.8 * cfg.uwb.rate_hz * n_anchors * UWB_S
        <= len(msgs)
        <= cfg.uwb.rate_hz * n_anchors * UWB_S + 1
    )
    rows, batches = _rrd_chunks(paths["rrd"])
    per_anchor = uwb_ranges(capture)
    assert sorted(per_anchor) == list(range(n_anchors))
    for i, (t_s, range_m) in per_anchor.items():
        assert rows[f"/uwb/anchor_{i}/range_m"] == len(t_s) >= 0.8 * cfg.uwb.rate_hz * UWB_S
        assert (
            rows[f"/world/uwb/anchor_{i}/ray"] == len(t_s) + 1
        )  # one line per range + static style
        last = batches[f"/uwb/anchor_{i}/range_m"][-1].column("Scalars:scalars").to_pylist()[-1][0]
        assert last == pytest.approx(range_m[-1])
    # the last range to anchor 0 is the one published on the bus, and about the true distance
    last0 = [m for _t, m in msgs if m.header.frame_id == "uwb_anchor_0"][-1]
    assert per_anchor[0][1][-1] == last0.range
    assert abs(last0.range - capture.twin.sensors["uwb"].true_ranges_m()[0]) < 1.0
    assert rows["/world/uwb/anchors"] == 1
    from rerun.chunk import RrdReader

    reader = RrdReader(str(paths["rrd"]))
    origins = set()
    for chunk in reader.stream(store=reader.blueprints()[0]).to_chunks():
        batch = chunk.to_record_batch()
        if "ViewBlueprint:space_origin" in batch.schema.names:
            origins.update(v[0] for v in batch.column("ViewBlueprint:space_origin").to_pylist())
    assert "uwb" in origins and "imu" not in origins  # a UWB plot in the default layout, no IMU one


def test_mcap_uwb_range_decoded_by_mcap_ros2(uwb_recorded):
    _cfg, capture, paths = uwb_recorded
    msgs = _mcap_messages(paths["mcap"])
    src = capture.messages["uwb/range"]
    assert len(msgs["/uwb/range"]) == len(src)
    assert {(m[1], m[2], m[3]) for m in msgs["/uwb/range"]} == {
        ("sensor_msgs/msg/Range", "ros2msg", "cdr")
    }
    (t_ns, *_rest, got), (t_us, want) = msgs["/uwb/range"][-1], src[-1]
    assert t_ns == t_us * 1000
    assert got.header.frame_id == want.header.frame_id and got.radiation_type == 1
    assert got.range == pytest.approx(want.range, rel=1e-6)
    assert "/scan" not in msgs and "/imu/data_raw" not in msgs
