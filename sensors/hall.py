"""Hall sensors of the hub motors and the driver's SC speed-pulse output.

Each M365-type hub motor has three hall sensors Ha, Hb, Hc and ``wheel.hall_pole_pairs``
pole pairs (15), so each sensor toggles every 360 / 30 = 12 degrees of wheel angle; the
three are a third of that (4 degrees) apart. The ZS-X11D1 driver's SC output changes state
whenever one of them does: 90 SC state changes per wheel revolution (thesis §2.2.1, fig. 2.13).

:class:`HallSensors` turns a chunk of the physics trajectory (wheel angles at
the physics step times) into the SC edges inside it, vectorised with numpy.
"""

from __future__ import annotations

import math

import numpy as np

from amr_twin.sensors.hall_edges import edge_kernel, solve_hermite, split_trajectory

N_SENSORS = 3
"""Ha, Hb, Hc."""

GLITCH_WIDTH_US = 20
"""Width of a spurious pulse on the SC line (a chattering hall sensor), microseconds."""


class HallSensors:
    """Hall sensors Ha/Hb/Hc and the SC output of every wheel's driver.

    Parameters
    ----------
    n_wheels : int
        Number of wheels (2: index 0 left, 1 right).
    pole_pairs : int
        The motor's pole pairs (``wheel.hall_pole_pairs``): a sensor toggles every
        ``360 / (2 pole_pairs)`` degrees of wheel angle (:attr:`pitch_rad`).
    misalignment_deg : float or array_like, shape (3,) or (n_wheels, 3)
        Mounting error of each sensor, degrees of wheel angle, added to its
        nominal offset (0, 1/3 and 2/3 of a pitch: 0, 4, 8 degrees at 15 pole pairs). Default 0.
    jitter_us : float
        Standard deviation of a Gaussian timing jitter on each SC edge,
        microseconds (optocoupler/driver latency spread). Default 0.
    hysteresis_deg : float
        Width of each latch's hysteresis band, degrees of wheel angle: a sensor toggles
        ``hysteresis_deg / 2`` past its boundary, forward or backward, so a wheel that stops
        at a boundary and springs back a little does not toggle it again. Default 0
        (every path); :meth:`edges_from_samples` only otherwise.
    seed : int or None
        Seed of the ``numpy.random.Generator`` that draws the jitter.
    native : bool
        Run the crossing loop of :meth:`edges_from_samples` in C when the helper builds
        (:mod:`amr_twin.sensors.hall_edges`, same edges; not with jitter or glitches);
        :attr:`engine` says which.
    """

    def __init__(
        self,
        n_wheels: int = 2,
        *,
        pole_pairs: int,
        misalignment_deg=0.0,
        jitter_us: float = 0.0,
        seed: int | None = None,
        native: bool = True,
        hysteresis_deg: float = 0.0,
    ):
        self.n_wheels = int(n_wheels)
        pitch_deg = 360.0 / (2 * int(pole_pairs))
        nominal_deg = pitch_deg / N_SENSORS * np.arange(N_SENSORS)
        mis = np.broadcast_to(np.asarray(misalignment_deg, dtype=float), (self.n_wheels, N_SENSORS))
        self.offset_rad = np.deg2rad(nominal_deg + mis)  # (n_wheels, 3)
        self.pitch_rad = np.deg2rad(pitch_deg)
        """Wheel angle between two toggles of one hall sensor, rad."""
        if not 0.0 <= hysteresis_deg < pitch_deg:
            raise ValueError(f"hysteresis_deg: {hysteresis_deg} must be in [0, {pitch_deg:g})")
        self.half_band_rad = math.radians(0.5 * hysteresis_deg)
        self.jitter_us = float(jitter_us)
        self._rng = np.random.default_rng(seed)
        self._count = np.zeros((self.n_wheels, N_SENSORS), dtype=np.int64)
        # fault injection (amr_twin/sim/fault_injector.py): stuck sensors, glitches on the SC line
        self.stuck = [[False] * N_SENSORS for _ in range(self.n_wheels)]
        self.glitch_rate_hz = [0.0] * self.n_wheels
        self._glitch_rng = np.random.default_rng([0 if seed is None else seed, 3])
        self._kernel, self.engine = edge_kernel(
            self.offset_rad, self.pitch_rad, self.half_band_rad, native
        )

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
        if self.half_band_rad:
            raise ValueError(
                "HallSensors.edges: the dense path has no hysteresis; use edges_from_samples"
            )
        t_us = np.asarray(t_us, dtype=np.int64)
        angle = np.asarray(angle_rad, dtype=float).reshape(len(t_us), self.n_wheels)
        count = self._lattice_index(angle)  # (n+1, W, 3)
        self._count = count[-1].copy()
        found = self._crossings(count)
        if found is None:
            return np.empty(0, np.int64), np.empty(0, np.int64)
        step, wheel, theta = found
        a0, a1 = angle[step, wheel], angle[step + 1, wheel]
        frac = (theta - a0) / (a1 - a0)
        return self._stamp(t_us, step, wheel, frac)

    def _crossings(self, count: np.ndarray):
        """Lattice crossings between consecutive rows of ``count`` (n+1, W, 3).

        Returns ``(step, wheel, theta_rad)`` of every crossing, or None.
        """
        n0, n1 = count[:-1], count[1:]  # (n, W, 3)
        crossings = np.abs(n1 - n0).ravel()
        total = int(crossings.sum())
        if total == 0:
            return None
        n_steps = len(count) - 1
        step, wheel, sensor = np.unravel_index(
            np.repeat(np.arange(crossings.size), crossings), (n_steps, self.n_wheels, N_SENSORS)
        )
        first = np.repeat(np.cumsum(crossings) - crossings, crossings)
        k = np.arange(total) - first  # 0.. within each (step, sensor)
        start = n0[step, wheel, sensor]
        forward = n1[step, wheel, sensor] > start
        lattice = np.where(forward, start + 1 + k, start - k)
        theta = self.offset_rad[wheel, sensor] + self.pitch_rad * lattice
        return step, wheel, theta

    def _stamp(self, t_us: np.ndarray, step: np.ndarray, wheel: np.ndarray, frac: np.ndarray):
        """Edge times from the fraction of each crossing's interval; sorted."""
        t0, t1 = t_us[step], t_us[step + 1]
        t_edge = t0 + frac * (t1 - t0)
        total = len(t_edge)
        if self.jitter_us > 0.0:
            t_edge = t_edge + self._rng.normal(0.0, self.jitter_us, total)
        edge_t = np.clip(np.rint(t_edge).astype(np.int64), t_us[0] + 1, t_us[-1])
        edge_t = np.maximum(edge_t, t0 + 1) if self.jitter_us == 0.0 else edge_t
        order = np.argsort(edge_t, kind="stable")
        return edge_t[order], wheel[order].astype(np.int64)

    def edges_from_samples(self, ts: list[int], rows: list[list[float]]) -> list[tuple[int, int]]:
        """SC edges from sparse samples of angle and speed (cubic Hermite in between): sorted
        ``(t_us, wheel)`` edges.

        Same edges as :meth:`edges` on the densely interpolated trajectory, but each crossing
        time is solved on the cubic directly, so the cost grows with the number of edges, not of
        physics steps.

        ``rows[i]`` holds the angles of all wheels then their speeds at ``ts[i]`` (further
        values in a row are ignored: the loop passes its sensor rows as they are).
        A chunk holds a few samples and a few edges, where numpy's per-call cost
        would dominate (``min``/``max`` of two floats are written as conditional
        expressions: same results, a third of the cost); the crossing loop runs in C
        when the helper is built (same edges), here otherwise or with jitter or glitches. Intervals
        where a wheel's speed changes sign (it may cross a boundary twice) are first split into 8
        sub-intervals.
        """
        nw = self.n_wheels
        jitter = self.jitter_us > 0.0
        if self._kernel is not None and not jitter and not any(self.glitch_rate_hz):
            edges = self._kernel.edges(
                ts, rows, self.stuck, self._count
            )  # resamples as below, in C
            if edges is not None:
                edges.sort(key=_edge_time)
                return edges
        for w in range(nw):
            speeds = [r[nw + w] for r in rows]
            if any(a * b < 0 for a, b in zip(speeds, speeds[1:])):
                samples = np.array(rows)
                t_arr, q, v = split_trajectory(
                    np.array(ts, np.int64), samples[:, :nw], samples[:, nw : 2 * nw], 8
                )
                ts, rows = t_arr.tolist(), np.hstack([q, v]).tolist()
                break
        pitch, offsets, floor, hb = (
            self.pitch_rad,
            self.offset_rad.tolist(),
            math.floor,
            self.half_band_rad,
        )
        t_first, t_last = ts[0] + 1, ts[-1]
        intervals = range(len(ts) - 1)
        edges: list[tuple[int, int]] = []
        for w in range(nw):
            angles = [r[w] for r in rows]
            speeds = [r[nw + w] for r in rows]
            for k, off in enumerate(offsets[w]):
                if self.stuck[w][k]:
                    continue
                count = int(self._count[w, k])
                for i in intervals:
                    q1 = angles[i + 1]
                    c1 = floor((q1 - off - hb) / pitch)  # forward: toggles hb past the boundary
                    up = c1 > count
                    if not up:
                        c1 = floor((q1 - off + hb) / pitch)  # backward: hb before it
                        if c1 >= count:
                            continue
                    q0, t0, span = angles[i], ts[i], ts[i + 1] - ts[i]
                    h = span * 1e-6
                    m0, m1 = speeds[i] * h, speeds[i + 1] * h
                    shift = hb if up else -hb
                    for lattice in range(count + 1, c1 + 1) if up else range(count, c1, -1):
                        s = solve_hermite(q0, q1, m0, m1, off + pitch * lattice + shift)
                        t = t0 + s * span
                        if jitter:
                            t += float(self._rng.normal(0.0, self.jitter_us))
                        t = round(t)  # min(t_last, max(t_first, round(t)))
                        t = t if t > t_first else t_first
                        edges.append((t if t < t_last else t_last, w))
                    count = c1
                self._count[w, k] = count
            if self.glitch_rate_hz[w] > 0.0:
                edges.extend(self._glitches(w, t_first, t_last))
        edges.sort(key=_edge_time)
        return edges

    def set_stuck(self, wheel: int, sensor: int, stuck: bool, angle_rad: float) -> None:
        """Freeze hall ``sensor`` (0 Ha, 1 Hb, 2 Hc) of ``wheel``, or free it again.

        A stuck sensor never toggles: the SC line loses its changes. Freed, it takes
        the level of the present wheel angle ``angle_rad`` without an edge.
        """
        self.stuck[wheel][sensor] = bool(stuck)
        if not stuck:
            self._count[wheel, sensor] = math.floor(
                (angle_rad - self.offset_rad[wheel, sensor]) / self.pitch_rad
            )

    def _glitches(self, wheel: int, t_first: int, t_last: int) -> list[tuple[int, int]]:
        """Spurious SC pulses of ``wheel`` in [t_first, t_last] us: Poisson at ``glitch_rate_hz``.

        Each glitch is a pulse, two changes :data:`GLITCH_WIDTH_US` apart (EMI on the line).
        """
        span_us = t_last - t_first
        if span_us <= 0:
            return []
        rng = self._glitch_rng
        n = int(rng.poisson(self.glitch_rate_hz[wheel] * span_us * 1e-6))
        out = []
        for t in sorted(rng.integers(t_first, t_last + 1, n).tolist()):
            out.append((t, wheel))
            out.append((min(t_last, t + GLITCH_WIDTH_US), wheel))
        return out


def _edge_time(edge: tuple[int, int]) -> int:
    return edge[0]
