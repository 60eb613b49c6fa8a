"""Adafruit 9-DOF IMU: LSM303DLHC accelerometer/magnetometer and L3GD20 gyroscope.

The thesis (§2.2.2, App. D) names the board, not its chips; the Adafruit 9-DOF
breakout carries an ST LSM303DLHC (3-axis accelerometer and magnetometer) and an
ST L3GD20 (3-axis gyroscope), which is what is modelled here. The true signals
come from MuJoCo's ``accelerometer``, ``gyro`` and ``magnetometer`` sensors on the
``amr/imu`` site (frame ``imu_link``, REP-103 axes): specific force (m/s^2, +9.81
on z at rest), body rate (rad/s) and the world field ``opt.magnetic`` (T).

Each axis of each sensor is corrupted as (see :func:`corrupt`)::

    y = quantise(clip((1 + s) * x + b0 + b_walk(t) + n, +-range), resolution)

with a turn-on bias ``b0 ~ N(0, bias_sigma)`` and a scale error ``s ~ N(0,
scale_sigma)`` drawn once, a bias random walk ``b_walk`` with increments
``N(0, walk * sqrt(dt))``, and white noise ``n ~ N(0, density * sqrt(rate))``
(the discrete-time convention of Kalibr's IMU noise model). The parameters and
their datasheet sources are in the ``imu:`` section of ``models/amr/amr.yaml``.

Published on the bus at ``rate_hz`` by clock events: ``sensor_msgs/Imu`` on
``imu/data_raw`` (no orientation: ``orientation_covariance[0] = -1``) and
``sensor_msgs/MagneticField`` on ``imu/mag``, both stamped with the sample time
and delivered at that time (no latency is modelled: the sample instant, the stamp
and the delivery coincide). Standalone, each sample is a clock event that reads
``MjData`` at its instant. In the twin (:meth:`ImuSensor.start` with the loop's
grid) the loop copies the true values on its record grid while the physics steps,
the errors of the samples taken so far are drawn in one batch (same numbers as
one by one), and each message goes out from a publishing clock event at its
sample instant, which does not stop the physics unless a subscriber could act on
it sooner (:meth:`amr_twin.ros.bus.Bus.lookahead_us`). The covariance arrays of the
messages are shared and read-only.

Covariances say what a reading's error is on the *raw* topic (:func:`covariances`):
per axis the white noise, the turn-on bias (the datasheet's zero-rate / zero-g
level, uncalibrated: 10 deg/s on the gyro) and the quantisation, ``noise^2 +
bias_sigma^2 + resolution^2 / 12``. A node that fuses ``imu/data_raw`` as it is
thus trusts the gyro to 10 deg/s, not to its 0.05 deg/s noise; the calibration
step that earns the noise level is the rest mean of the first seconds (the twin's
EKF does it, ``ekf.imu_rest_calibration_s``, :mod:`amr_twin.controllers.ekf`).
This module does not import mujoco: it reads ``MjData.sensordata`` by address.
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass

import numpy as np

from amr_twin.ros.bus import Bus
from amr_twin.ros.tf_buffer import IMU_FRAME
from amr_twin.sim.clock import VirtualClock
from amr_twin.model.config_sections import ImuCfg
from amr_twin.ros.geometry_messages import Quaternion, Vector3
from amr_twin.ros.messages import Header, Time
from amr_twin.ros.sensor_messages import Imu, MagneticField

US = 1_000_000
SENSOR_NAMES = ("amr/imu_accel", "amr/imu_gyro", "amr/imu_mag")
"""MuJoCo sensors read by the IMU: accelerometer, gyro, magnetometer (3 values each)."""


@dataclass
class AxisModel:
    """Error model of one 3-axis sensor; all arrays shape (3,), in the sensor's SI unit."""

    bias: np.ndarray
    scale: np.ndarray
    noise_sigma: float
    walk_sigma: float
    range_max: float
    resolution: np.ndarray


def corrupt(true: np.ndarray, model: AxisModel, rng: np.random.Generator, dt_s: float) -> np.ndarray:
    """Advance the bias random walk by ``dt_s`` and return one corrupted sample.

    Parameters
    ----------
    true : ndarray, shape (3,)
        True value in the sensor frame (m/s^2, rad/s or T).
    model : AxisModel
        Error state; ``model.bias`` is updated in place by the random walk.
    rng : numpy.random.Generator
        Source of the noise (three normals for the walk, three for the noise).
    dt_s : float
        Time since the previous sample, s.

    Returns
    -------
    ndarray, shape (3,)
        Scaled, biased, noisy, saturated and quantised reading.
    """
    if model.walk_sigma > 0:
        model.bias += rng.normal(0.0, model.walk_sigma * np.sqrt(dt_s), 3)
    noise = rng.normal(0.0, model.noise_sigma, 3) if model.noise_sigma > 0 else 0.0
    y = np.clip((1.0 + model.scale) * true + model.bias + noise, -model.range_max, model.range_max)
    res = model.resolution
    return np.where(res > 0, np.round(y / np.where(res > 0, res, 1.0)) * res, y)


def axis_models(cfg: ImuCfg, rng: np.random.Generator) -> dict[str, AxisModel]:
    """Draw the turn-on biases and scale errors of accel, gyro and mag (in that order)."""
    rate = cfg.rate_hz
    return {
        "accel": AxisModel(rng.normal(0.0, cfg.accel_bias_sigma_m_s2, 3), rng.normal(0.0, cfg.accel_scale_sigma, 3),
                           cfg.accel_noise_density_m_s2_sqrt_hz * np.sqrt(rate), cfg.accel_bias_walk_m_s2_sqrt_s,
                           cfg.accel_range_m_s2, np.full(3, cfg.accel_resolution_m_s2)),
        "gyro": AxisModel(rng.normal(0.0, cfg.gyro_bias_sigma_rad_s, 3), rng.normal(0.0, cfg.gyro_scale_sigma, 3),
                          cfg.gyro_noise_density_rad_s_sqrt_hz * np.sqrt(rate), cfg.gyro_bias_walk_rad_s_sqrt_s,
                          cfg.gyro_range_rad_s, np.full(3, cfg.gyro_resolution_rad_s)),
        "mag": AxisModel(rng.normal(0.0, cfg.mag_bias_sigma_t, 3), np.zeros(3), cfg.mag_noise_t, 0.0,
                         cfg.mag_range_t,
                         np.array([cfg.mag_resolution_xy_t, cfg.mag_resolution_xy_t, cfg.mag_resolution_z_t])),
    }


def covariances(models: dict[str, AxisModel], cfg: ImuCfg) -> dict[str, np.ndarray]:
    """Row-major 3x3 covariances (9,) of the raw readings of ``accel``, ``gyro`` and ``mag``.

    Diagonal: ``noise_sigma^2 + bias_sigma^2 + resolution^2 / 12`` per axis (SI units
    squared), the error of one uncalibrated reading (module docstring).
    """
    bias = {"accel": cfg.accel_bias_sigma_m_s2, "gyro": cfg.gyro_bias_sigma_rad_s, "mag": cfg.mag_bias_sigma_t}
    out = {}
    for name, m in models.items():
        variance = m.noise_sigma ** 2 + bias[name] ** 2 + np.asarray(m.resolution, float) ** 2 / 12.0
        out[name] = np.diag(np.broadcast_to(variance, (3,))).ravel()
    return out


class ImuSensor:
    """The Adafruit 9-DOF on floor (b), sampled by clock events and published on the bus.

    Parameters
    ----------
    model, data : mujoco.MjModel, mujoco.MjData
        The compiled twin (sensors named as in :data:`SENSOR_NAMES`).
    clock : VirtualClock
        Shared clock; one event per sample.
    bus : Bus
        Publishes ``imu/data_raw`` and ``imu/mag``.
    cfg : ImuCfg
        Noise parameters (``imu:`` section of the parameter file).
    seed : int or None
        Seed of the ``numpy.random.Generator`` (biases, scale errors, noise).
    autostart : bool
        Schedule the first sample at the current clock time.
    """

    def __init__(self, model, data, clock: VirtualClock, bus: Bus, cfg: ImuCfg, seed: int | None = 0,
                 frame_id: str = IMU_FRAME, autostart: bool = True):
        self.data, self.clock, self.bus, self.cfg, self.frame_id = data, clock, bus, cfg, frame_id
        self._adr = [int(model.sensor(name).adr[0]) for name in SENSOR_NAMES]
        self.rng = np.random.default_rng(seed)
        self.models = axis_models(cfg, self.rng)
        self.period_us = int(round(US / cfg.rate_hz))
        self.dt_s = self.period_us / US
        self.pub_imu = bus.advertise("imu/data_raw", Imu)
        self.pub_mag = bus.advertise("imu/mag", MagneticField)
        self._cov = covariances(self.models, cfg)
        self._orientation_cov = np.zeros(9)
        self._orientation_cov[0] = -1.0  # orientation not provided (data_raw)
        ms = [self.models[k] for k in ("accel", "gyro", "mag")]
        self._bias = np.concatenate([m.bias for m in ms])  # (9,) evolving biases
        for i, m in enumerate(ms):
            m.bias = self._bias[3 * i:3 * i + 3]  # views: the models show the current bias
        self._scale = np.concatenate([m.scale for m in ms])
        self._noise = np.repeat([m.noise_sigma for m in ms], 3)
        self._walk = np.repeat([m.walk_sigma * np.sqrt(self.dt_s) for m in ms], 3)
        self._range = np.repeat([m.range_max for m in ms], 3)
        self._res = np.concatenate([m.resolution for m in ms])
        self._quantised = self._res > 0  # axes with a resolution of 0 are not quantised
        self._res = np.where(self._quantised, self._res, 1.0)
        self._inv_res = 1.0 / self._res
        self.seq = 0
        self._handle = None
        self._samplers: list | None = None  # the loop's grid samplers while fed by the loop
        self._start_us = 0
        self._true_t: list[int] = []  # instants of the true values taken on the grid, us
        self._true = np.zeros((64, 9))  # the true values, first len(_true_t) rows
        self._ready: deque[tuple[int, list[float]]] = deque()  # (t_us, 9 readings) to publish
        a = self._adr
        self._sd9 = data.sensordata[a[0]:a[0] + 9] if a[1] == a[0] + 3 and a[2] == a[0] + 6 else None
        for cov in (*self._cov.values(), self._orientation_cov):
            cov.flags.writeable = False  # shared by every message: read-only
        if autostart:
            self.start()

    def start(self, grid_us: int | None = None, samplers: list | None = None) -> None:
        """Start sampling at the next multiple of ``period_us`` (absolute time), then every period.

        Parameters
        ----------
        grid_us : int, optional
            The simulation loop's sampling grid, us. With ``samplers``, when
            ``period_us`` is a multiple of it, the loop samples the true values
            on its grid while it steps (:meth:`on_grid`) and the messages go out
            from *publishing* clock events at the sample instants: the physics
            is not stopped for them (:mod:`amr_twin.sim.clock`). Otherwise each
            sample is a clock event that reads ``MjData`` at its instant.
        samplers : list, optional
            The loop's list of grid samplers; :meth:`on_grid` is appended to it.
        """
        if self._handle is not None:
            return
        first_us = self._start_us = -(-self.clock.now_us // self.period_us) * self.period_us
        if grid_us and samplers is not None and self.period_us % int(grid_us) == 0:
            self._samplers = samplers
            samplers.append(self.on_grid)
            self._handle = self.clock.schedule(first_us, self._publish_next,
                                               publishes=("imu/data_raw", "imu/mag"))
        else:
            self._handle = self.clock.schedule(first_us, self._tick)

    def stop(self) -> None:
        """Stop sampling (samples taken and not yet published are discarded)."""
        if self._handle is not None:
            self._handle.cancel()
            self._handle = None
        if self._samplers is not None:
            self._samplers.remove(self.on_grid)
            self._samplers = None
        self._true_t.clear()
        self._ready.clear()

    def true_values(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(accel m/s^2, gyro rad/s, mag T), each shape (3,), without errors."""
        sd = self.data.sensordata
        return tuple(sd[a:a + 3].copy() for a in self._adr)

    def _true9(self) -> np.ndarray:
        if self._sd9 is not None:
            return self._sd9.copy()
        sd, a = self.data.sensordata, self._adr
        return np.concatenate((sd[a[0]:a[0] + 3], sd[a[1]:a[1] + 3], sd[a[2]:a[2] + 3]))

    def corrupt_batch(self, true: np.ndarray) -> np.ndarray:
        """Corrupt ``n`` consecutive samples, advancing the error state by ``n`` periods.

        Same arithmetic as :func:`corrupt` on the nine axes at once: per sample the
        random walk, then noise, scale, clip and quantisation; the generator draws
        9 walk normals then 9 noise normals per sample, so a batch gives the same
        numbers as ``n`` calls of :meth:`sample`.

        Parameters
        ----------
        true : ndarray, shape (n, 9)
            True accel (m/s^2), gyro (rad/s) and mag (T) values, sensor frame.

        Returns
        -------
        ndarray, shape (n, 9)
            Readings in the same units.
        """
        n = len(true)
        z = self.rng.standard_normal((n, 18))
        steps = np.empty((n + 1, 9))
        steps[0] = self._bias
        steps[1:] = self._walk * z[:, :9]
        bias = np.cumsum(steps, axis=0)[1:]  # sequential: bias_k = bias_(k-1) + walk_k
        self._bias[:] = bias[-1]
        y = (1.0 + self._scale) * true + bias + self._noise * z[:, 9:]
        y = np.minimum(np.maximum(y, -self._range), self._range)
        return np.where(self._quantised, np.round(y * self._inv_res) * self._res, y)

    def sample(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """One corrupted sample (accel, gyro, mag) of ``MjData`` now, advancing the error state by one period."""
        y = self.corrupt_batch(self._true9()[None, :])[0]
        return y[0:3], y[3:6], y[6:9]

    def on_grid(self, t_us: int) -> None:
        """The loop's grid sampler: keep the true values at the sample instants (physics at ``t_us``)."""
        if t_us % self.period_us == 0 and t_us >= self._start_us:
            n = len(self._true_t)
            if n == len(self._true):
                self._true = np.concatenate([self._true, np.zeros_like(self._true)])
            if self._sd9 is not None:
                self._true[n] = self._sd9
            else:
                self._true[n] = self._true9()
            self._true_t.append(t_us)

    def _publish_next(self) -> None:
        """Publishing event: the sample taken on the grid at this instant goes out."""
        now = self.clock.now_us
        self._handle = self.clock.schedule(now + self.period_us, self._publish_next,
                                           publishes=("imu/data_raw", "imu/mag"))
        if not self._ready:
            if not self._true_t:
                raise RuntimeError(f"IMU sample at t_us={now} was not taken on the loop's grid")
            y = self.corrupt_batch(self._true[:len(self._true_t)])
            self._ready.extend(zip(self._true_t, y.tolist()))
            self._true_t.clear()
        t_us, y = self._ready.popleft()
        if t_us != now:
            raise RuntimeError(f"IMU sample at t_us={now} was not taken on the loop's grid (got {t_us})")
        self._publish(y)

    def _tick(self) -> None:
        self._handle = self.clock.schedule(self.clock.now_us + self.period_us, self._tick)
        self._publish(self.corrupt_batch(self._true9()[None, :])[0].tolist())

    def _publish(self, a: list[float]) -> None:
        """Publish the readings ``a`` (accel, gyro, mag: 9 values) stamped now."""
        stamp = Time.from_us(self.clock.now_us)
        self.seq += 1
        header = Header(self.seq, stamp, self.frame_id)
        cov = self._cov  # positional fields (ROS order): header, orientation, covariances and vectors
        self.pub_imu.publish(Imu(header, Quaternion(), self._orientation_cov, Vector3(a[3], a[4], a[5]),
                                 cov["gyro"], Vector3(a[0], a[1], a[2]), cov["accel"]))
        self.pub_mag.publish(MagneticField(Header(self.seq, stamp, self.frame_id), Vector3(a[6], a[7], a[8]),
                                           cov["mag"]))
