"""People in the scan: clusters of unmapped returns tracked from scan to scan, their motion
predicted.

Reasons and measurements: docs/explanation/navigation.md#amr_twinnavigationpeople."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components


@dataclass(frozen=True)
class People:
    """Confirmed tracks at ``t_s``: positions ``xy_m`` (N, 2) and velocities ``v_m_s`` (N, 2) in
    ``map``; ``intent_m_s`` (N, 2) each one's last walking velocity (zero if never seen walking;
    None: unknown)."""

    t_s: float
    xy_m: np.ndarray
    v_m_s: np.ndarray
    intent_m_s: np.ndarray | None = None

    def __len__(self) -> int:
        return len(self.xy_m)

    def at(self, t_s: np.ndarray, horizon_s: float) -> np.ndarray:
        """Positions (N, len(t_s), 2) at instants ``t_s`` (s), constant velocity for at most
        ``horizon_s``."""
        dt = np.clip(np.asarray(t_s, float) - self.t_s, 0.0, horizon_s)
        return self.xy_m[:, None, :] + self.v_m_s[:, None, :] * dt[None, :, None]


NOBODY = People(0.0, np.zeros((0, 2)), np.zeros((0, 2)))


def clusters(points_xy_m: np.ndarray, join_m: float) -> np.ndarray:
    """Cluster label (P,) of each point (P, 2): single linkage at ``join_m``."""
    p = np.asarray(points_xy_m, float).reshape(-1, 2)
    if len(p) == 0:
        return np.zeros(0, int)
    d2 = ((p[:, None, :] - p[None, :, :]) ** 2).sum(-1)
    i, j = np.nonzero(np.triu(d2 <= join_m * join_m, 1))
    graph = coo_matrix((np.ones(len(i)), (i, j)), shape=(len(p), len(p)))
    return connected_components(graph, directed=False)[1]


class PeopleTracker:
    """Tracks of person-sized clusters of unmapped returns (module docstring)."""

    def __init__(
        self,
        *,
        join_m: float = 0.3,
        max_size_m: float = 0.6,
        range_m: float = 3.5,
        gate_m: float = 0.3,
        max_speed_m_s: float = 2.5,
        alpha: float = 0.6,
        beta: float = 0.25,
        keep_s: float = 0.6,
        confirm: int = 2,
        min_speed_m_s: float = 0.25,
        horizon_s: float = 2.5,
        moved_m: float = 0.5,
    ):
        self.join_m, self.max_size_m, self.range_m, self.gate_m = (
            join_m,
            max_size_m,
            range_m,
            gate_m,
        )
        self.max_speed_m_s, self.alpha, self.beta, self.keep_s = max_speed_m_s, alpha, beta, keep_s
        self.confirm, self.min_speed_m_s, self.horizon_s = int(confirm), min_speed_m_s, horizon_s
        self.moved_m = moved_m
        self.clear()

    def detect(self, points_xy_m: np.ndarray, t_s: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Person-sized clusters of ``points_xy_m`` (P, 2) seen at ``t_s`` (P,): centres (M, 2),
        times (M,)."""
        labels = clusters(points_xy_m, self.join_m)
        if len(labels) == 0:
            return np.zeros((0, 2)), np.zeros(0)
        n = labels.max() + 1
        count = np.bincount(labels, minlength=n)
        centre = np.column_stack(
            [np.bincount(labels, points_xy_m[:, k], n) / count for k in range(2)]
        )
        t = np.bincount(labels, t_s, n) / count
        lo = np.full((n, 2), np.inf)
        hi = np.full((n, 2), -np.inf)
        np.minimum.at(lo, labels, points_xy_m)
        np.maximum.at(hi, labels, points_xy_m)
        small = np.hypot(*(hi - lo).T) <= self.max_size_m
        return centre[small], t[small]

    def update(
        self, points_xy_m: np.ndarray, t_s: np.ndarray, origin_xy_m, scan_end_s: float
    ) -> None:
        """One scan's unmapped returns ``points_xy_m`` (P, 2) in ``map``, their instants ``t_s``
        (P,), seen from ``origin_xy_m`` (the laser, to keep those within ``range_m``) by the scan
        that ended at ``scan_end_s`` (a track unseen since ``keep_s`` before it is dropped)."""
        p, t = np.asarray(points_xy_m, float).reshape(-1, 2), np.asarray(t_s, float)
        near = np.hypot(*(p - np.asarray(origin_xy_m, float)).T) <= self.range_m
        centre, t_c = self.detect(p[near], t[near])
        now = float(scan_end_s)
        free = np.ones(len(self._xy), bool)
        used = np.zeros(len(centre), bool)
        if len(self._xy) and len(centre):
            dt = np.maximum(t_c[:, None] - self._t[None, :], 1e-3)
            guess = self._xy[None, :, :] + self._v[None, :, :] * dt[..., None]
            d = np.hypot(*(centre[:, None, :] - guess).transpose(2, 0, 1))
            ok = d <= self.gate_m + self.max_speed_m_s * dt
            for flat in np.argsort(np.where(ok, d, np.inf), axis=None):
                i, j = np.unravel_index(flat, d.shape)
                if not ok[i, j]:
                    break
                if used[i] or not free[j]:
                    continue
                used[i], free[j] = True, False
                r = centre[i] - guess[i, j]
                self._xy[j] = guess[i, j] + self.alpha * r
                v = self._v[j] + self.beta * r / dt[i, j]
                speed = float(np.hypot(*v))
                self._v[j] = v if speed <= self.max_speed_m_s else v * (self.max_speed_m_s / speed)
                self._t[j], self._hits[j] = t_c[i], self._hits[j] + 1
                if speed >= self.min_speed_m_s:
                    self._intent[j] = self._v[j]
                self._moved[j] |= bool(np.hypot(*(self._xy[j] - self._first[j])) > self.moved_m)
        alive = self._t >= now - self.keep_s
        new = ~used
        k = int(new.sum())
        self._xy = np.vstack([self._xy[alive], centre[new]])
        self._first = np.vstack([self._first[alive], centre[new]])
        self._moved = np.concatenate([self._moved[alive], np.zeros(k, bool)])
        self._v = np.vstack([self._v[alive], np.zeros((k, 2))])
        self._intent = np.vstack([self._intent[alive], np.zeros((k, 2))])
        self._t = np.concatenate([self._t[alive], t_c[new]])
        self._hits = np.concatenate([self._hits[alive], np.ones(k, int)])

    def people(self) -> People:
        """The people: confirmed tracks that have moved (module docstring), those standing with zero
        velocity."""
        keep = (self._hits >= self.confirm) & self._moved
        if not keep.any():
            return NOBODY
        v = self._v[keep].copy()
        v[np.hypot(v[:, 0], v[:, 1]) < self.min_speed_m_s] = 0.0
        t = self._t[keep]
        xy = self._xy[keep] + v * (t.max() - t)[:, None]  # brought to one instant
        return People(float(t.max()), xy, v, self._intent[keep].copy())

    def clear(self) -> None:
        """Forget every track."""
        self._xy, self._first, self._v = np.zeros((0, 2)), np.zeros((0, 2)), np.zeros((0, 2))
        self._intent = np.zeros((0, 2))
        self._t, self._hits, self._moved = np.zeros(0), np.zeros(0, int), np.zeros(0, bool)
