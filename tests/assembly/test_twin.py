"""The loop: publishing events run while the physics is ahead, without changing the run."""

import numpy as np
import pytest

from amr_twin.model.config import load_config
from amr_twin.assembly.twin import Twin, TwinOptions
from amr_twin.recording.recorder import attach_recorder, recorder_of

SENSOR_TOPICS = ("odom", "tf", "imu/data_raw", "imu/mag", "scan")


@pytest.fixture(scope="module")
def cfg():
    return load_config()


def _run(cfg, subscribe: bool, duration_s: float = 1.5):
    twin = Twin(cfg, TwinOptions(sensors=("imu", "lidar"), world="empty"))
    attach_recorder(twin)
    taps = []
    twin.bus.add_tap(lambda topic, msg, t_us: taps.append((topic, t_us, msg)))
    if subscribe:  # zero-latency subscribers: every publishing event becomes a sync point
        for topic in SENSOR_TOPICS:
            twin.bus.subscribe(topic, lambda msg: None)
    chunks = []
    step = twin._step_physics
    twin._step_physics = lambda n: (chunks.append(n), step(n))
    twin.client.angular(45.0, 0.5)
    twin.advance(duration_s)
    return twin, taps, chunks


def test_subscribers_force_sync_points_but_the_run_is_bit_identical(cfg):
    free, free_taps, free_chunks = _run(cfg, subscribe=False)
    synced, synced_taps, synced_chunks = _run(cfg, subscribe=True)
    assert (
        len(free_chunks) < len(synced_chunks) / 3
    )  # odometry, IMU, LiDAR did not stop the physics
    a, b = recorder_of(free).series(), recorder_of(synced).series()
    for name in ("t_s", "true_rpm", "pose", "pwm_counts", "odom"):
        assert np.array_equal(getattr(a, name), getattr(b, name)), name
    assert [(t, u) for t, u, _ in free_taps] == [(t, u) for t, u, _ in synced_taps]
    scans = [(m.ranges.tobytes(), m.header.stamp.to_us()) for t, _, m in free_taps if t == "scan"]
    assert scans == [
        (m.ranges.tobytes(), m.header.stamp.to_us()) for t, _, m in synced_taps if t == "scan"
    ]
    imu = [m.angular_velocity.z for t, _, m in free_taps if t == "imu/data_raw"]
    assert imu == [m.angular_velocity.z for t, _, m in synced_taps if t == "imu/data_raw"]


def test_sensor_messages_are_delivered_at_their_instants(cfg):
    twin, taps, _ = _run(cfg, subscribe=False, duration_s=0.5)
    imu = [(t_us, m.header.stamp.to_us()) for topic, t_us, m in taps if topic == "imu/data_raw"]
    assert [t for t, _ in imu] == [s for _, s in imu] == list(range(0, 500_001, 10_000))
    scans = [(t_us, m.header.stamp.to_us()) for topic, t_us, m in taps if topic == "scan"]
    lidar = twin.sensors["lidar"]
    # stamp = first beam; delivered at the first 20 ms pose sample at or after the last beam
    last_beam = (
        lidar.scan_us - lidar.beam_dt_us
    )  # stamped at the rotation's last beam (the A1 spins clockwise)
    assert scans == [(200_000, last_beam), (380_000, lidar.scan_us + last_beam)]


def test_a_subscriber_acting_on_odometry_acts_at_its_time(cfg):
    def reacting():
        twin = Twin(cfg, TwinOptions(world="empty"))
        attach_recorder(twin)

        def on_odom(msg):
            if msg.header.stamp.to_us() == 1_060_000:  # between firmware timer ticks
                twin.client.linear(0.3)

        twin.bus.subscribe("odom", on_odom)
        twin.advance(2.0)
        return recorder_of(twin).series()

    def by_hand():
        twin = Twin(cfg, TwinOptions(world="empty"))
        attach_recorder(twin)
        twin.bus.subscribe("odom", lambda msg: None)
        twin.advance(1.06)
        twin.client.linear(0.3)
        twin.advance(0.94)
        return recorder_of(twin).series()

    a, b = reacting(), by_hand()
    assert a.commands == b.commands and a.commands[0][0] == pytest.approx(1.06)
    assert np.array_equal(a.true_rpm, b.true_rpm) and np.abs(a.true_rpm[-1]).min() > 10


def test_a_synced_event_sees_the_physics_at_its_instant(cfg):
    twin = Twin(cfg, TwinOptions(world="empty"))
    seen = []
    for t_us in (123_456, 400_000, 777_001):
        twin.clock.schedule(t_us, lambda t_us=t_us: seen.append((t_us, twin.t_phys_us)))
    twin.client.linear(0.5)
    twin.advance(1.0)
    assert [t_phys - t for t, t_phys in seen] == [544, 0, 999]  # the first step at or after t


@pytest.mark.parametrize("firmware", ["faithful", "improved"])
def test_without_the_odometry_node_the_drive_is_the_same_to_the_bit(cfg, firmware):
    """TwinOptions(nodes=()) (a sweep point) drops the odom/tf publisher and nothing else."""
    series = {}
    for odometry in (True, False):
        twin = Twin(
            cfg,
            TwinOptions(world="empty", firmware=firmware, nodes=("odometry",) if odometry else ()),
        )
        attach_recorder(twin)
        twin.client.angular(60.0, -1.0)
        twin.advance(2.0)
        series[odometry] = recorder_of(twin).series()
    on, off = series[True], series[False]
    assert len(on.odom) > 50 and len(off.odom) == 0
    for name in ("pose", "pwm_counts", "current_a", "battery_v"):
        np.testing.assert_array_equal(getattr(on, name), getattr(off, name), err_msg=name)
    for wheel in (0, 1):
        np.testing.assert_array_equal(on.published[wheel], off.published[wheel])


def test_without_the_robot_visuals_the_run_is_the_same_to_the_bit(cfg):
    """TwinOptions(visuals=False) (a run nothing draws) leaves the visual geoms out of the model and
    nothing else: the same drive, contacts and loads, and no recording can be attached to it."""
    from amr_twin.recording.rerun_capture import attach

    twins = {}
    for visuals in (True, False):
        twin = Twin(
            load_config(overrides={"payload.mass_kg": 30.0}),
            TwinOptions(world="warehouse", start_xy_yaw=(-8.0, 0.5, 0.5), visuals=visuals),
        )
        attach_recorder(twin)
        twin.client.linear(0.7)
        twin.advance(1.5)
        twin.client.angular(-60.0, 0.0)
        twin.advance(1.0)
        twins[visuals] = twin
    on, off = twins[True], twins[False]
    assert off.physics.model.ngeom < on.physics.model.ngeom - 30
    assert on.physics.data.ncon == off.physics.data.ncon >= 6
    for name in ("pose", "true_rpm", "pwm_counts", "current_a", "battery_v"):
        np.testing.assert_array_equal(
            getattr(recorder_of(on).series(), name),
            getattr(recorder_of(off).series(), name),
            err_msg=name,
        )
    np.testing.assert_array_equal(on.physics.data.qvel, off.physics.data.qvel)
    attach(on)
    with pytest.raises(ValueError, match="visuals=True"):
        attach(off)


def test_without_island_discovery_the_run_is_the_same_to_the_bit():
    """The build disables MuJoCo's constraint islands (one robot: at most one island); with them on,
    a run with a payload off centre, a turn and a stop gives the same bits."""
    import mujoco

    cfg = load_config(overrides={"payload.mass_kg": 40.0, "payload.xy_m": [0.1, 0.05]})
    series = {}
    for islands in (False, True):
        twin = Twin(cfg, TwinOptions(world="empty", visuals=False))
        attach_recorder(twin)
        flag = int(mujoco.mjtDisableBit.mjDSBL_ISLAND)
        assert twin.physics.model.opt.disableflags & flag
        if islands:
            twin.physics.model.opt.disableflags &= ~flag
        twin.client.linear(0.7)
        twin.advance(1.5)
        twin.client.angular(-60.0, 0.0)
        twin.advance(1.0)
        twin.client.stop()
        twin.advance(0.5)
        series[islands] = recorder_of(twin).series()
    for name in ("pose", "true_rpm", "current_a"):
        np.testing.assert_array_equal(
            getattr(series[False], name), getattr(series[True], name), err_msg=name
        )
