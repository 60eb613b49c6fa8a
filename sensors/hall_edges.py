"""SC edge times inside a chunk of sampled wheel angles and speeds: the numerics of the hall
sensors.

Between two samples the wheel angle follows the cubic Hermite curve through the
angles and speeds; each lattice crossing is solved on it by Newton's method
(:func:`solve_hermite`) and rounded to the microsecond. Intervals where a speed changes
sign are first resampled (:func:`split_trajectory`). :class:`EdgeKernel` runs the
crossing loop of :meth:`amr_twin.sensors.hall.HallSensors.edges_from_samples` in C
(``hall_edges.c``, built at first use by :mod:`amr_twin.base.native_build`; 14.5 us of
Python per 10 ms tick of the loop, measured in a 16 s run) with the same results: that
method is its Python twin.
"""

from __future__ import annotations

import ctypes
from array import array
from pathlib import Path

import numpy as np

from amr_twin.base.native_build import address, open_helper

C_SOURCE = Path(__file__).with_name("hall_edges.c")
MAX_EDGES = 4096
"""Edges the C helper returns from one chunk; with more, the Python twin runs."""


class EdgeKernel:
    """The C crossing loop for ``n_wheels`` wheels with hall ``offsets_rad`` (n_wheels, 3) and
    ``pitch_rad``."""

    def __init__(
        self, lib: ctypes.PyDLL, offsets_rad: np.ndarray, pitch_rad: float, half_band_rad: float
    ):
        fn = self._fn = lib.hall_edges
        p, i, d = ctypes.c_void_p, ctypes.c_int, ctypes.c_double
        fn.restype, fn.argtypes = i, [i, p, p, i, i, p, p, d, d, p, p, p, i]
        reverses = self._reverses = lib.hall_reverses
        reverses.restype, reverses.argtypes = i, [i, p, i, i]
        self.n_wheels = len(offsets_rad)
        self._offsets = np.ascontiguousarray(offsets_rad, float)
        self._pitch = float(pitch_rad)
        self._stuck = np.zeros(self._offsets.shape, np.intc)
        self._stuck_as = [[False] * self._offsets.shape[1] for _ in range(self.n_wheels)]
        self._any_stuck = False
        self._count = np.zeros(self._offsets.shape, np.int64)
        self._t, self._w = np.zeros(MAX_EDGES, np.int64), np.zeros(MAX_EDGES, np.intc)
        self._fixed = (
            address(self._offsets),
            address(self._stuck),
            self._pitch,
            float(half_band_rad),
            address(self._count),
            address(self._t),
            address(self._w),
            MAX_EDGES,
        )

    def edges(
        self, ts: list[int], rows: list[list[float]], stuck: list[list[bool]], count: np.ndarray
    ) -> list[tuple[int, int]] | None:
        """``(t_us, wheel)`` edges in the order wheel, sensor, interval, crossing (not sorted), from
        the toggle counts ``count`` (n_wheels, 3), the free sensors' final ones written back; None
        beyond
        :data:`MAX_EDGES` edges. ``rows`` as
        :meth:`amr_twin.sensors.hall.HallSensors.edges_from_samples` takes them; a chunk where a
        speed changes sign is resampled first (:func:`split_trajectory`), as there. The samples go
        to C as flat arrays of the angles and speeds only (``array``: a third of the cost of numpy's
        conversion of nested lists)."""
        nw = self.n_wheels
        ncol = 2 * nw
        t = array("q", ts)
        flat: list[float] = []
        extend = flat.extend
        for row in rows:
            extend(row[:ncol])
        r = array("d", flat)
        if self._reverses(len(t) - 1, address(r), ncol, nw):
            samples = np.frombuffer(r).reshape(len(t), ncol)
            t_new, q, v = split_trajectory(
                np.frombuffer(t, np.int64), samples[:, :nw], samples[:, nw:], 8
            )
            t, r = t_new, np.ascontiguousarray(np.hstack([q, v]))
        if stuck != self._stuck_as:
            self._stuck[:] = stuck
            self._stuck_as = [list(s) for s in stuck]
            self._any_stuck = any(map(any, stuck))
        offsets_at, stuck_at, pitch, half_band, count_at, t_at, w_at, cap = self._fixed
        self._count[:] = count
        n = self._fn(
            len(t) - 1,
            address(t),
            address(r),
            ncol,
            nw,
            offsets_at,
            stuck_at,
            pitch,
            half_band,
            count_at,
            t_at,
            w_at,
            cap,
        )
        if n < 0:
            return None
        if self._any_stuck:
            free = self._stuck == 0
            count[free] = self._count[free]
        else:
            count[:] = self._count
        return list(zip(self._t[:n].tolist(), self._w[:n].tolist()))


def edge_kernel(
    offsets_rad: np.ndarray, pitch_rad: float, half_band_rad: float = 0.0, native: bool = True
) -> tuple[EdgeKernel | None, str]:
    """``(kernel, engine)``: the C crossing loop (None without the helper) and ``"C"`` or ``"Python
    (<why>)"``."""
    lib, engine = open_helper(C_SOURCE, native)
    return (
        EdgeKernel(lib, offsets_rad, pitch_rad, half_band_rad) if lib is not None else None
    ), engine


def solve_hermite(q0: float, q1: float, m0: float, m1: float, theta: float) -> float:
    """Fraction s in [0, 1] where the Hermite cubic through (q0, m0), (q1, m1) equals theta.

    Newton's method on the cubic's power form ``((a s + b) s + c) s + d`` from the
    linear guess, clamped to [0, 1], until a step is below ``STEP_TOL`` (four steps
    at most). The result differs from the exact root by about 1e-16; the edge time
    ``t0 + s * span`` (span <= 10 ms) is rounded to the microsecond, so that
    difference never shows.
    """
    dq = q1 - q0
    s = (theta - q0) / dq if q1 != q0 else 0.5
    s = s if s > 0.0 else 0.0
    s = s if s < 1.0 else 1.0
    a = m0 + m1 - 2.0 * dq
    b = 3.0 * dq - 2.0 * m0 - m1
    d = q0 - theta
    a3, b2 = 3.0 * a, 2.0 * b
    for _ in range(4):
        df = (a3 * s + b2) * s + m0
        if abs(df) < 1e-12:
            break
        step = (((a * s + b) * s + m0) * s + d) / df
        s -= step
        s = s if s > 0.0 else 0.0
        s = s if s < 1.0 else 1.0
        if abs(step) < STEP_TOL:
            break
    return s


STEP_TOL = 1e-13
"""Newton step of :func:`_solve_hermite` below which the root is taken as found (a fraction of
the interval: 1e-9 us of a 10 ms interval)."""


def split_trajectory(t_us: np.ndarray, q: np.ndarray, v: np.ndarray, parts: int):
    """Resample a Hermite trajectory with ``parts`` sub-intervals per interval."""
    frac = np.arange(parts) / parts
    t_new = (t_us[:-1, None] + frac * np.diff(t_us)[:, None]).ravel()
    t_new = np.append(np.rint(t_new).astype(np.int64), t_us[-1])
    i = np.clip(np.searchsorted(t_us, t_new, side="right") - 1, 0, len(t_us) - 2)
    h = ((t_us[i + 1] - t_us[i]) * 1e-6)[:, None]
    s = ((t_new - t_us[i]) * 1e-6)[:, None] / h
    s2, s3 = s * s, s * s * s
    q_new = (
        (2 * s3 - 3 * s2 + 1) * q[i]
        + (s3 - 2 * s2 + s) * h * v[i]
        + (-2 * s3 + 3 * s2) * q[i + 1]
        + (s3 - s2) * h * v[i + 1]
    )
    v_new = (
        (6 * s2 - 6 * s) * q[i] / h
        + (3 * s2 - 4 * s + 1) * v[i]
        + (-6 * s2 + 6 * s) * q[i + 1] / h
        + (3 * s2 - 2 * s) * v[i + 1]
    )
    return t_new, q_new, v_new
