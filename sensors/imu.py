"""Adafruit 9-DOF IMU: LSM303DLHC accelerometer/magnetometer and L3GD20 gyroscope.

The thesis (§2.2.2, App. D) names the board, not its chips; the Adafruit 9-DOF
breakout carries an ST LSM303DLHC (3-axis accelerometer and magnetometer) and an
ST L3GD20 (3-axis gyroscope), which is what is modelled here. The true signals
come from MuJoCo's ``accelerometer``, ``gyro`` and ``magnetometer`` sensors on the
``amr/imu`` site (frame ``imu_link``, REP-103 axes): specific force (m/s^2, +9.81
on z at rest), body rate (rad/s) and the world field ``opt.magnetic`` (T).

Reasons and measurements: docs/explanation/fusion.md#amr_twinsensorsimu.

Part of the physics layer (``PHYSICS_LAYER``): a sensor: reads MuJoCo's accelerometer, gyro and
magnetometer values where they lie in MjData (by address, in C on the loop's grid)."""

from __future__ import annotations

from collections import deque

import numpy as np

from amr_twin.ros.bus import Bus
from amr_twin.ros.tf_buffer import IMU_FRAME
from amr_twin.base.clock import VirtualClock
from amr_twin.model.config_sensors import ImuCfg
from amr_twin.ros.geometry_messages import Quaternion, Vector3
from amr_twin.ros.messages import Header, Time
from amr_twin.ros.sensor_messages import Imu, MagneticField
from amr_twin.sensors.imu_errors import ErrorStream, axis_models, covariances
from amr_twin.sim.grid_rows import GridRows, gather
from amr_twin.base.native_build import address

PHYSICS_LAYER = True

US = 1_000_000
SENSOR_NAMES = ("imu_accel", "imu_gyro", "imu_mag")
"""MuJoCo sensors read by the IMU: accelerometer, gyro, magnetometer (3 values each)."""


class ImuSensor:
    """The Adafruit 9-DOF on floor (b), sampled by clock events and published on the bus.

    Parameters
    ----------
    physics : amr_twin.sim.physics.Physics
        The compiled twin (its robot's sensors named as in :data:`SENSOR_NAMES`, after its prefix).
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
    native : bool
        Corrupt the samples in C when the helper builds (same bits; :attr:`engine` says which runs).
    """

    def __init__(
        self,
        physics,
        clock: VirtualClock,
        bus: Bus,
        cfg: ImuCfg,
        seed: int | None = 0,
        frame_id: str = IMU_FRAME,
        autostart: bool = True,
        native: bool = True,
    ):
        model, data = physics.model, physics.data
        self.data, self.clock, self.bus, self.cfg, self.frame_id = data, clock, bus, cfg, frame_id
        self._adr = [int(model.sensor(physics.prefix + name).adr[0]) for name in SENSOR_NAMES]
        self.rng = np.random.default_rng(seed)
        self.models = axis_models(cfg, self.rng)
        self.period_us = int(round(US / cfg.rate_hz))
        self.dt_s = self.period_us / US
        self.pub_imu = bus.advertise("imu/data_raw", Imu)
        self.pub_mag = bus.advertise("imu/mag", MagneticField)
        self._cov = covariances(self.models, cfg)
        self._orientation_cov = np.zeros(9)
        self._orientation_cov[0] = -1.0  # orientation not provided (data_raw)
        self.errors = ErrorStream(self.models, self.dt_s, self.rng, native)
        """The nine axes' error state (the models' ``bias`` arrays are views of ``errors.bias``)."""
        self.engine = self.errors.engine
        self.seq = 0
        self._handle = None
        self._samplers: list | None = None  # the loop's grid samplers while fed by the loop
        self._start_us = 0
        self._native = native
        self._true: GridRows | None = (
            None  # the true values (9) taken on the loop's grid, after their instants
        )
        self._ready: deque[tuple[int, Imu, MagneticField]] = deque()  # (t_us, messages) to publish
        a = self._adr
        self._sd9 = (
            data.sensordata[a[0] : a[0] + 9] if a[1] == a[0] + 3 and a[2] == a[0] + 6 else None
        )
        self._true9_list = (
            self._sd9.tolist if self._sd9 is not None else lambda: self._true9().tolist()
        )
        for cov in (*self._cov.values(), self._orientation_cov):
            cov.flags.writeable = False  # shared by every message: read-only
        self._fast = (
            bus.publish,
            frame_id,
            self._orientation_cov,
            self._cov["gyro"],
            self._cov["accel"],
            self._cov["mag"],
        )
        if autostart:
            self.start()

    def start(self, grid_us: int | None = None, samplers: list | None = None) -> None:
        """Start sampling at the next multiple of ``period_us`` (absolute time), then every period.

        Parameters
        ----------
        grid_us : int, optional
            The simulation loop's sampling grid, us. With ``samplers``, when
            ``period_us`` is a multiple of it, the loop samples the true values
            on its grid while it steps (a :class:`~amr_twin.sim.grid_rows.GridRows`,
            in C when the loop runs its grid there) and the messages go out
            from *publishing* clock events at the sample instants: the physics
            is not stopped for them (:mod:`amr_twin.base.clock`). Otherwise each
            sample is a clock event that reads ``MjData`` at its instant.
        samplers : list, optional
            The loop's list of grid samplers; the true values' keeper is appended to it.
        """
        if self._handle is not None:
            return
        first_us = self._start_us = -(-self.clock.now_us // self.period_us) * self.period_us
        if grid_us and samplers is not None and self.period_us % int(grid_us) == 0:
            self._samplers = samplers
            at, a = (
                address(self.data.sensordata),
                self._adr,
            )  # the three vectors' values, where they lie
            c_row = (
                gather([at + 8 * (a[v] + k) for v in range(3) for k in range(3)])
                if self._native
                else None
            )
            self._true = GridRows(9, self.period_us, self._true9_list, c_row, start_us=first_us)
            samplers.append(self._true)
            self._handle = self.clock.schedule_every(
                first_us, self.period_us, self._publish_next, publishes=("imu/data_raw", "imu/mag")
            )
        else:
            self._handle = self.clock.schedule_every(first_us, self.period_us, self._tick)

    def stop(self) -> None:
        """Stop sampling (samples taken and not yet published are discarded)."""
        if self._handle is not None:
            self._handle.cancel()
            self._handle = None
        if self._samplers is not None:
            self._samplers.remove(self._true)
            self._samplers = None
        self._true = None
        self._ready.clear()

    def true_values(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(accel m/s^2, gyro rad/s, mag T), each shape (3,), without errors."""
        sd = self.data.sensordata
        return tuple(sd[a : a + 3].copy() for a in self._adr)

    def _true9(self) -> np.ndarray:
        if self._sd9 is not None:
            return self._sd9.copy()
        sd, a = self.data.sensordata, self._adr
        return np.concatenate((sd[a[0] : a[0] + 3], sd[a[1] : a[1] + 3], sd[a[2] : a[2] + 3]))

    def corrupt_batch(self, true: np.ndarray) -> np.ndarray:
        """Corrupt ``n`` consecutive samples (n, 9), advancing the error state by ``n`` periods.

        True accel (m/s^2), gyro (rad/s) and mag (T) values in, readings in the same
        units out (:meth:`amr_twin.sensors.imu_errors.ErrorStream.corrupt_python`, or its C
        twin); a batch gives the same numbers as ``n`` calls of :meth:`sample`.
        """
        return self.errors.corrupt_batch(true)

    def sample(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """One corrupted sample (accel, gyro, mag) of ``MjData`` now, advancing the error state by
        one period."""
        y = self.corrupt_batch(self._true9()[None, :])[0]
        return y[0:3], y[3:6], y[6:9]

    def _publish_next(self) -> None:
        """Publishing event: the sample taken on the grid at this instant goes out. The first event
        after a chunk corrupts the chunk's samples in one batch and builds their messages (one
        warm pass); each event then publishes its own pair."""
        now = self.clock.now_us
        if not self._ready:
            true = self._true.take() if self._true is not None else np.zeros((0, 10))
            if not len(true):
                raise RuntimeError(f"IMU sample at t_us={now} was not taken on the loop's grid")
            y = self.errors.corrupt_batch(np.ascontiguousarray(true[:, 1:]))
            self._ready.extend(self._messages(true[:, 0].astype(np.int64).tolist(), y.tolist()))
        t_us, imu, mag = self._ready.popleft()
        if t_us != now:
            raise RuntimeError(
                f"IMU sample at t_us={now} was not taken on the loop's grid (got {t_us})"
            )
        self.seq = imu.header.seq
        publish = self._fast[0]
        publish("imu/data_raw", imu)
        publish("imu/mag", mag)

    def _messages(self, ts_us: list[int], ys: list[list[float]]) -> list[tuple]:
        """``(t_us, Imu, MagneticField)`` of the readings ``ys`` (9 each) stamped ``ts_us``,
        numbered on from :attr:`seq`."""
        _publish, frame, orientation_cov, gyro_cov, accel_cov, mag_cov = self._fast
        out, from_us = [], Time.from_us
        for seq, (t_us, a) in enumerate(zip(ts_us, ys), self.seq + 1):
            stamp = from_us(t_us)
            imu = Imu(
                Header(seq, stamp, frame),
                Quaternion(),
                orientation_cov,
                Vector3(a[3], a[4], a[5]),
                gyro_cov,
                Vector3(a[0], a[1], a[2]),
                accel_cov,
            )
            mag = MagneticField(Header(seq, stamp, frame), Vector3(a[6], a[7], a[8]), mag_cov)
            out.append((t_us, imu, mag))
        return out

    def _tick(self) -> None:
        self._publish(self.corrupt_batch(self._true9()[None, :])[0].tolist())

    def _publish(self, a: list[float]) -> None:
        """Publish the readings ``a`` (accel, gyro, mag: 9 values) stamped now."""
        stamp = Time.from_us(self.clock.now_us)
        seq = self.seq = self.seq + 1
        # positional fields (ROS order): header, orientation, covariances and vectors; the
        # covariance arrays are shared, read-only (one tuple read: this runs at 100 Hz on cold
        # caches)
        publish, frame, orientation_cov, gyro_cov, accel_cov, mag_cov = self._fast
        publish(
            "imu/data_raw",
            Imu(
                Header(seq, stamp, frame),
                Quaternion(),
                orientation_cov,
                Vector3(a[3], a[4], a[5]),
                gyro_cov,
                Vector3(a[0], a[1], a[2]),
                accel_cov,
            ),
        )
        publish(
            "imu/mag", MagneticField(Header(seq, stamp, frame), Vector3(a[6], a[7], a[8]), mag_cov)
        )
