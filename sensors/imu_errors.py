"""Error model of the Adafruit 9-DOF's three sensors: turn-on bias, scale, random walk, noise,
limits.

Each axis is corrupted as (:func:`corrupt`, module :mod:`amr_twin.sensors.imu`)::

    y = quantise(clip((1 + s) * x + b0 + b_walk(t) + n, +-range), resolution)

:func:`axis_models` draws the turn-on biases and scale errors, :func:`covariances` gives
the raw readings' covariances, and :class:`ErrorStream` corrupts the nine axes of
consecutive samples at once: the errors that do not depend on the true values (the
bias walk and the white noise) are drawn ahead in blocks of :data:`ERROR_BLOCK` samples,
the same numbers as drawing per sample, and the rest runs in C when a compiler is at
hand (``imu_errors.c``, :mod:`amr_twin.base.native_build`: about 2 us for a batch
against 40 us of numpy; 9 us per 10 ms tick of the loop measured in a 8 s run).
:meth:`ErrorStream.corrupt_python` is its Python twin: the same operations in the same
order, the same bits.
"""

from __future__ import annotations

import ctypes
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from amr_twin.model.config_sensors import ImuCfg
from amr_twin.base.c_layout import register
from amr_twin.base.native_build import address, c_array, open_helper

C_SOURCE = Path(__file__).with_name("imu_errors.c")
ERROR_BLOCK = 256
"""Samples whose errors (bias walk, white noise) are drawn at once: 2.56 s at 100 Hz."""


@dataclass
class AxisModel:
    """Error model of one 3-axis sensor; all arrays shape (3,), in the sensor's SI unit."""

    bias: np.ndarray
    scale: np.ndarray
    noise_sigma: float
    walk_sigma: float
    range_max: float
    resolution: np.ndarray


def corrupt(
    true: np.ndarray, model: AxisModel, rng: np.random.Generator, dt_s: float
) -> np.ndarray:
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
        "accel": AxisModel(
            rng.normal(0.0, cfg.accel_bias_sigma_m_s2, 3),
            rng.normal(0.0, cfg.accel_scale_sigma, 3),
            cfg.accel_noise_density_m_s2_sqrt_hz * np.sqrt(rate),
            cfg.accel_bias_walk_m_s2_sqrt_s,
            cfg.accel_range_m_s2,
            np.full(3, cfg.accel_resolution_m_s2),
        ),
        "gyro": AxisModel(
            rng.normal(0.0, cfg.gyro_bias_sigma_rad_s, 3),
            rng.normal(0.0, cfg.gyro_scale_sigma, 3),
            cfg.gyro_noise_density_rad_s_sqrt_hz * np.sqrt(rate),
            cfg.gyro_bias_walk_rad_s_sqrt_s,
            cfg.gyro_range_rad_s,
            np.full(3, cfg.gyro_resolution_rad_s),
        ),
        "mag": AxisModel(
            rng.normal(0.0, cfg.mag_bias_sigma_t, 3),
            np.zeros(3),
            cfg.mag_noise_t,
            0.0,
            cfg.mag_range_t,
            np.array([cfg.mag_resolution_xy_t, cfg.mag_resolution_xy_t, cfg.mag_resolution_z_t]),
        ),
    }


def covariances(models: dict[str, AxisModel], cfg: ImuCfg) -> dict[str, np.ndarray]:
    """Row-major 3x3 covariances (9,) of the raw readings of ``accel``, ``gyro`` and ``mag``.

    Diagonal: ``noise_sigma^2 + bias_sigma^2 + resolution^2 / 12`` per axis (SI units
    squared), the error of one uncalibrated reading (module docstring).
    """
    bias = {
        "accel": cfg.accel_bias_sigma_m_s2,
        "gyro": cfg.gyro_bias_sigma_rad_s,
        "mag": cfg.mag_bias_sigma_t,
    }
    out = {}
    for name, m in models.items():
        variance = m.noise_sigma**2 + bias[name] ** 2 + np.asarray(m.resolution, float) ** 2 / 12.0
        out[name] = np.diag(np.broadcast_to(variance, (3,))).ravel()
    return out


class _Axes(ctypes.Structure):
    """``imu_axes`` of imu_errors.c."""

    _fields_ = [
        ("scale1", ctypes.c_double * 9),
        ("range", ctypes.c_double * 9),
        ("res", ctypes.c_double * 9),
        ("inv_res", ctypes.c_double * 9),
        ("quantised", ctypes.c_int * 9),
    ]


register(C_SOURCE, imu_axes=_Axes)


class ErrorStream:
    """The error state of the nine axes (accel, gyro, mag) and the corruption of consecutive
    samples.

    Parameters
    ----------
    models : dict of AxisModel
        ``accel``, ``gyro``, ``mag`` (:func:`axis_models`); their ``bias`` arrays become
        views of :attr:`bias` (they show the bias of the last sample taken).
    dt_s : float
        Sample period, s.
    rng : numpy.random.Generator
        Draws 9 walk normals then 9 noise normals per sample.
    native : bool
        Use the C helper when it builds (:attr:`engine` says which runs).
    """

    def __init__(
        self,
        models: dict[str, AxisModel],
        dt_s: float,
        rng: np.random.Generator,
        native: bool = True,
    ):
        ms = [models[k] for k in ("accel", "gyro", "mag")]
        self.rng = rng
        self.bias = np.concatenate([m.bias for m in ms])
        """(9,) the biases of the last sample taken (turn-on bias plus walk)."""
        for i, m in enumerate(ms):
            m.bias = self.bias[3 * i : 3 * i + 3]
        self._block: tuple[np.ndarray, np.ndarray] | None = (
            None  # biases and noise drawn ahead (m, 9) x 2
        )
        self._pos = 0  # rows of _block used
        self._scale = np.concatenate([m.scale for m in ms])
        self._noise = np.repeat([m.noise_sigma for m in ms], 3)
        self._walk = np.repeat([m.walk_sigma * np.sqrt(dt_s) for m in ms], 3)
        self._range = np.repeat([m.range_max for m in ms], 3)
        res = np.concatenate([m.resolution for m in ms])
        self._quantised = res > 0  # axes with a resolution of 0 are not quantised
        self._res = np.where(self._quantised, res, 1.0)
        self._inv_res = 1.0 / self._res
        self.corrupt_batch = self.corrupt_python
        """``corrupt_batch(true)``: the C helper when built, else :meth:`corrupt_python`."""
        lib, self.engine = open_helper(C_SOURCE, native)
        if lib is not None:
            self._use_native(lib)

    def _use_native(self, lib) -> None:
        axes = self._axes = _Axes()
        axes.scale1[:] = (1.0 + self._scale).tolist()
        axes.range[:], axes.res[:] = self._range.tolist(), self._res.tolist()
        axes.inv_res[:], axes.quantised[:] = (
            self._inv_res.tolist(),
            [int(q) for q in self._quantised],
        )
        fn = lib.imu_corrupt
        fn.restype = None
        fn.argtypes = [ctypes.c_int] + [ctypes.c_void_p] * 5
        axes_p = ctypes.addressof(axes)

        def corrupt_c(true: np.ndarray) -> np.ndarray:
            n = len(true)
            true = c_array(true, np.float64)
            bias, noise = self._errors(n)
            out = np.empty((n, 9))
            fn(n, address(true), address(bias), address(noise), axes_p, address(out))
            return out

        self.corrupt_batch = corrupt_c

    def corrupt_python(self, true: np.ndarray) -> np.ndarray:
        """Readings (n, 9) of the true values ``true`` (n, 9) of ``n`` consecutive samples (SI
        units).

        Per sample the random walk, then noise, scale, clip and quantisation, as
        :func:`corrupt`; advances the error state by ``n`` periods.
        """
        bias, noise = self._errors(len(true))
        y = (1.0 + self._scale) * true + bias + noise
        y = np.minimum(np.maximum(y, -self._range), self._range)
        return np.where(self._quantised, np.round(y * self._inv_res) * self._res, y)

    def _errors(self, n: int) -> tuple[np.ndarray, np.ndarray]:
        """The biases (n, 9) and white noise (n, 9) of the next ``n`` samples; advances
        :attr:`bias`.

        Drawn ahead, :data:`ERROR_BLOCK` samples at a time (18 standard normals per sample:
        9 for the walk, then 9 for the noise), the walk as a running sum from the bias of the
        block's previous sample: the same numbers as drawing per sample.
        """
        pos, block = self._pos, self._block
        if block is None or pos + n > len(block[0]):
            m = max(n, ERROR_BLOCK)
            z = self.rng.standard_normal((m, 18))
            steps = np.empty((m + 1, 9))
            steps[0] = (
                self.bias if block is None else block[0][-1]
            )  # turn-on bias, then the walk's end
            steps[1:] = self._walk * z[:, :9]
            fresh = (
                np.cumsum(steps, axis=0)[1:],
                self._noise * z[:, 9:],
            )  # bias_k = bias_(k-1) + walk_k
            if block is not None and pos < len(block[0]):  # the rows not used yet come first
                fresh = tuple(np.concatenate([old[pos:], new]) for old, new in zip(block, fresh))
            block, pos = self._block, self._pos = fresh, 0
        bias, noise = block[0][pos : pos + n], block[1][pos : pos + n]
        self._pos = pos + n
        self.bias[:] = bias[-1]
        return bias, noise
