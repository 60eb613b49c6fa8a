"""Adafruit 9-DOF IMU: error model (pure), rest reading, gyro-integrated turn, seeds, messages."""

import math

import numpy as np
import pytest

from amr_twin.ros.bus import Bus
from amr_twin.base.clock import VirtualClock
from amr_twin.model.config import load_config
from amr_twin.sensors.imu import ImuSensor
from amr_twin.sensors.imu_errors import AxisModel, axis_models, corrupt


def test_corrupt_quantises_saturates_and_walks():
    rng = np.random.default_rng(0)
    m = AxisModel(
        bias=np.zeros(3),
        scale=np.zeros(3),
        noise_sigma=0.0,
        walk_sigma=0.0,
        range_max=2.0,
        resolution=np.array([0.5, 0.5, 0.0]),
    )
    assert corrupt(np.array([0.74, -5.0, 0.123]), m, rng, 0.01).tolist() == [0.5, -2.0, 0.123]
    m.walk_sigma = 1.0
    corrupt(np.zeros(3), m, rng, 0.01)
    assert np.all(m.bias != 0) and np.all(np.abs(m.bias) < 1.0)


def test_error_state_is_seeded():
    cfg = load_config().imu
    a, b, c = (axis_models(cfg, np.random.default_rng(s)) for s in (1, 1, 2))
    assert np.array_equal(a["gyro"].bias, b["gyro"].bias) and not np.array_equal(
        a["gyro"].bias, c["gyro"].bias
    )
    assert a["gyro"].noise_sigma == pytest.approx(cfg.gyro_noise_density_rad_s_sqrt_hz * 10.0)


class Rig:
    """The robot on the empty floor with an IMU on its own clock, stepped by hand."""

    def __init__(self, overrides=None, seed=0):
        from amr_twin.model.build import build
        from amr_twin.sim.physics import Physics

        self.cfg = load_config(overrides=overrides or {})
        self.physics = Physics(build(self.cfg, world="empty").model)
        self.physics.settle(0.5)
        self.clock = VirtualClock()
        self.bus = Bus(self.clock)
        self.imu_msgs, self.mag_msgs = [], []
        self.bus.subscribe("imu/data_raw", self.imu_msgs.append)
        self.bus.subscribe("imu/mag", self.mag_msgs.append)
        self.imu = ImuSensor(self.physics, self.clock, self.bus, self.cfg.imu, seed=seed)

    def run(self, duration_s):
        n = int(round(duration_s * 100))
        for _ in range(n):
            self.clock.run_until(self.clock.now_us)  # the sample at now
            self.physics.step(10)
            self.clock.run_until(self.clock.now_us + 10_000 - 1)
            self.clock.set_time(self.clock.now_us + 1)

    def gyro(self):
        return np.array(
            [
                [m.angular_velocity.x, m.angular_velocity.y, m.angular_velocity.z]
                for m in self.imu_msgs
            ]
        )

    def accel(self):
        return np.array(
            [
                [m.linear_acceleration.x, m.linear_acceleration.y, m.linear_acceleration.z]
                for m in self.imu_msgs
            ]
        )


NO_BIAS = {
    "imu.accel_bias_sigma_m_s2": 0.0,
    "imu.accel_scale_sigma": 0.0,
    "imu.accel_bias_walk_m_s2_sqrt_s": 0.0,
}


def test_at_rest_the_acceleration_norm_is_g_within_noise():
    rig = Rig(NO_BIAS)
    rig.run(2.0)
    acc = rig.accel()
    assert len(acc) == 200
    sigma = rig.imu.models["accel"].noise_sigma
    norms = np.linalg.norm(acc, axis=1)
    assert (
        abs(norms.mean() - 9.81)
        < 3 * sigma / math.sqrt(len(norms)) + rig.cfg.imu.accel_resolution_m_s2
    )
    assert np.abs(norms - 9.81).max() < 5 * sigma + rig.cfg.imu.accel_resolution_m_s2
    # with the datasheet's zero-g offsets the norm stays within their spread
    biased = Rig()
    biased.run(0.5)
    err = np.linalg.norm(biased.accel().mean(axis=0)) - 9.81
    assert abs(err) < 3 * math.sqrt(3) * biased.cfg.imu.accel_bias_sigma_m_s2


def test_gyro_integrated_over_a_90_degree_turn():
    rig = Rig()
    rig.run(1.0)  # rest: the zero-rate level is calibrated out, as a driver does at start-up
    bias = rig.gyro().mean(axis=0)
    n_rest = len(rig.imu_msgs)
    yaw0 = rig.physics.pose().yaw_rad
    rig.physics.motors.set(0, "drive", -1.0)
    rig.physics.motors.set(1, "drive", 1.0)
    while abs(math.remainder(rig.physics.pose().yaw_rad - yaw0, 2 * math.pi)) < math.radians(85):
        rig.run(0.01)
    for w in range(2):
        rig.physics.motors.set(w, "brake")
    rig.run(1.0)
    turned = math.remainder(rig.physics.pose().yaw_rad - yaw0, 2 * math.pi)
    assert 80 < math.degrees(turned) < 120  # the shorted motors stop it in about 0.3 s
    rate = rig.gyro()[n_rest:, 2] - bias[2]
    assert rate.max() > math.radians(30)
    integrated = rate.sum() * rig.imu.dt_s
    assert math.degrees(abs(integrated - turned)) < 1.0


def test_same_seed_bit_identical_other_seed_different():
    def record(seed):
        rig = Rig(seed=seed)
        rig.run(0.3)
        return np.concatenate([rig.accel(), rig.gyro()]).tobytes()

    assert record(3) == record(3) and record(3) != record(4)


def test_messages_frames_and_covariances():
    rig = Rig()
    rig.run(0.1)
    imu, mag = rig.imu_msgs[-1], rig.mag_msgs[-1]
    assert imu.header.frame_id == "imu_link" and mag.header.frame_id == "imu_link"
    assert [m.header.stamp.to_us() for m in rig.imu_msgs[:3]] == [0, 10_000, 20_000]
    assert imu.orientation_covariance[0] == -1.0
    cfg = rig.cfg.imu
    gyro_var = (
        rig.imu.models["gyro"].noise_sigma ** 2
        + cfg.gyro_bias_sigma_rad_s**2
        + cfg.gyro_resolution_rad_s**2 / 12
    )
    assert imu.angular_velocity_covariance.reshape(3, 3) == pytest.approx(np.diag([gyro_var] * 3))
    assert imu.linear_acceleration_covariance[8] > cfg.accel_bias_sigma_m_s2**2
    field = np.array([mag.magnetic_field.x, mag.magnetic_field.y, mag.magnetic_field.z])
    assert 20e-6 < np.linalg.norm(field) < 80e-6  # the earth's field, T


def test_a_batch_of_samples_draws_the_same_numbers_as_one_by_one():
    one, batch = Rig(seed=5), Rig(seed=5)
    true = np.random.default_rng(0).normal(0.0, 1.0, (40, 9)) * [
        1,
        1,
        10,
        0.1,
        0.1,
        0.1,
        4e-5,
        4e-5,
        4e-5,
    ]
    single = np.array([one.imu.corrupt_batch(x[None, :])[0] for x in true])
    many = np.concatenate([batch.imu.corrupt_batch(true[:7]), batch.imu.corrupt_batch(true[7:])])
    assert single.tobytes() == many.tobytes()
    assert np.array_equal(one.imu.models["gyro"].bias, batch.imu.models["gyro"].bias)
    assert not np.array_equal(
        one.imu.models["gyro"].bias, Rig(seed=5).imu.models["gyro"].bias
    )  # it walked


def test_fed_by_a_grid_the_messages_match_the_clock_event_ones():
    """The twin's way (true values taken on the loop's grid, publishing events) against reading
    MjData."""
    evented, fed = Rig(seed=2), Rig(seed=2)
    samplers = []
    fed.imu.stop()
    fed.imu.start(grid_us=10_000, samplers=samplers)
    for rig in (evented, fed):
        rig.physics.motors.set(0, "drive", -2.0)
        rig.physics.motors.set(1, "drive", 2.0)
    evented.run(0.3)
    samplers[0](0)
    for k in range(
        1, 30
    ):  # the physics runs ahead; the messages go out at their instants afterwards
        fed.physics.step(10)
        samplers[0](k * 10_000)
    fed.clock.run_until(290_000)
    assert len(fed.imu_msgs) == len(evented.imu_msgs) == 30
    for a, b in zip(fed.imu_msgs, evented.imu_msgs):
        assert a.header.stamp == b.header.stamp and a.angular_velocity == b.angular_velocity
        assert a.linear_acceleration == b.linear_acceleration
    assert abs(fed.imu_msgs[-1].angular_velocity.z) > 0.1


def test_raw_covariance_is_honest_about_the_turn_on_bias():
    """At rest the gyro's error (reading - truth) is inside 3 stated sigmas for every seed;
    the noise alone would not cover them."""
    z_scores, noise_z = [], []
    for seed in range(8):
        rig = Rig(seed=seed)
        rig.run(0.5)
        err = rig.gyro().mean(axis=0)  # at rest the true rate is ~0
        sigma = np.sqrt(np.diag(rig.imu_msgs[-1].angular_velocity_covariance.reshape(3, 3)))
        z_scores.append(np.abs(err) / sigma)
        noise_z.append(abs(err[2]) / rig.imu.models["gyro"].noise_sigma)
    assert np.max(z_scores) < 3.0
    assert max(noise_z) > 10  # what a noise-only covariance claims is wrong by far
