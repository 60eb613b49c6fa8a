"""Hall sensors of the hub motors and the driver's SC speed-pulse output.

Each M365-type hub motor has three hall sensors Ha, Hb, Hc and 15 pole pairs, so
each sensor toggles every 360 / 30 = 12 degrees of wheel angle; the three are
4 degrees apart. The ZS-X11D1 driver's SC output changes state whenever one of
them does: 90 SC state changes per wheel revolution (thesis §2.2.1, fig. 2.13).

:class:`HallSensors` turns a chunk of the physics trajectory (wheel angles at
the physics step times) into the SC edges inside it, vectorised with numpy.
"""

from __future__ import annotations

import numpy as np

SENSOR_PITCH_DEG = 12.0
"""Wheel angle between two toggles of one hall sensor, degrees (15 pole pairs)."""

SENSOR_SPACING_DEG = 4.0
"""Wheel angle between the three sensors' lattices, degrees."""

N_SENSORS = 3
"""Ha, Hb, Hc."""


class HallSensors:
    """Hall sensors Ha/Hb/Hc and the SC output of every wheel's driver.

    Parameters
    ----------
    n_wheels : int
        Number of wheels (2: index 0 left, 1 right).
    misalignment_deg : float or array_like, shape (3,) or (n_wheels, 3)
        Mounting error of each sensor, degrees of wheel angle, added to its
        nominal offset (0, 4, 8 degrees). Default 0.
    jitter_us : float
        Standard deviation of a Gaussian timing jitter on each SC edge,
        microseconds (optocoupler/driver latency spread). Default 0.
    seed : int or None
        Seed of the ``numpy.random.Generator`` that draws the jitter.
    """

    def __init__(self, n_wheels: int = 2, misalignment_deg=0.0, jitter_us: float = 0.0,
                 seed: int | None = None):
        self.n_wheels = int(n_wheels)
        nominal_deg = SENSOR_SPACING_DEG * np.arange(N_SENSORS)
        mis = np.broadcast_to(np.asarray(misalignment_deg, dtype=float),
                              (self.n_wheels, N_SENSORS))
        self.offset_rad = np.deg2rad(nominal_deg + mis)  # (n_wheels, 3)
        self.pitch_rad = np.deg2rad(SENSOR_PITCH_DEG)
        self.jitter_us = float(jitter_us)
        self._rng = np.random.default_rng(seed)
        self._count = np.zeros((self.n_wheels, N_SENSORS), dtype=np.int64)

    def _lattice_index(self, angle_rad: np.ndarray) -> np.ndarray:
        """Toggle count of every sensor, shape ``angle_rad.shape + (3,)``."""
        return np.floor((angle_rad[..., None] - self.offset_rad) / self.pitch_rad).astype(np.int64)

    def reset(self, angle_rad) -> None:
        """Set the sensor states from the wheel angles (rad, shape (n_wheels,))."""
        self._count = self._lattice_index(np.asarray(angle_rad, dtype=float))

    @property
    def states(self) -> np.ndarray:
        """Levels of (Ha, Hb, Hc) per wheel, shape (n_wheels, 3), 0 or 1."""
        return (self._count & 1).astype(np.int8)

    @property
    def sc_level(self) -> np.ndarray:
        """SC output level per wheel, shape (n_wheels,): Ha xor Hb xor Hc."""
        return np.bitwise_xor.reduce(self.states, axis=1)

    def edges(self, t_us, angle_rad) -> tuple[np.ndarray, np.ndarray]:
        """SC state changes inside one chunk of trajectory.

        Parameters
        ----------
        t_us : array_like of int64, shape (n+1,)
            Physics step times, microseconds, increasing.
        angle_rad : array_like, shape (n+1, n_wheels)
            Unwrapped wheel angles at ``t_us``, rad, positive = rolling forward.

        Returns
        -------
        edge_t_us : ndarray of int64
            Edge times in (t_us[0], t_us[-1]], sorted, microseconds. Inside a
            physics step the angle is interpolated linearly.
        edge_wheel : ndarray of int64
            Wheel index of each edge.
        """
        t_us = np.asarray(t_us, dtype=np.int64)
        angle = np.asarray(angle_rad, dtype=float).reshape(len(t_us), self.n_wheels)
        count = self._lattice_index(angle)                 # (n+1, W, 3)
        self._count = count[-1].copy()
        n0, n1 = count[:-1], count[1:]                      # (n, W, 3)
        crossings = np.abs(n1 - n0).ravel()
        total = int(crossings.sum())
        if total == 0:
            return np.empty(0, np.int64), np.empty(0, np.int64)
        n_steps = len(t_us) - 1
        step, wheel, sensor = np.unravel_index(np.repeat(np.arange(crossings.size), crossings),
                                               (n_steps, self.n_wheels, N_SENSORS))
        first = np.repeat(np.cumsum(crossings) - crossings, crossings)
        k = np.arange(total) - first                        # 0.. within each (step, sensor)
        start = n0[step, wheel, sensor]
        forward = n1[step, wheel, sensor] > start
        lattice = np.where(forward, start + 1 + k, start - k)
        theta = self.offset_rad[wheel, sensor] + self.pitch_rad * lattice
        a0, a1 = angle[step, wheel], angle[step + 1, wheel]
        t0, t1 = t_us[step], t_us[step + 1]
        frac = (theta - a0) / (a1 - a0)
        t_edge = t0 + frac * (t1 - t0)
        if self.jitter_us > 0.0:
            t_edge = t_edge + self._rng.normal(0.0, self.jitter_us, total)
        edge_t = np.clip(np.rint(t_edge).astype(np.int64), t_us[0] + 1, t_us[-1])
        edge_t = np.maximum(edge_t, t0 + 1) if self.jitter_us == 0.0 else edge_t
        order = np.argsort(edge_t, kind="stable")
        return edge_t[order], wheel[order].astype(np.int64)
