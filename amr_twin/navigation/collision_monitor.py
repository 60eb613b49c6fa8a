"""The collision monitor on raw scans (nav2's collision_monitor): approach and slowdown zones.

Reasons and measurements: docs/explanation/navigation.md#amr_twinnavigationcollision_monitor."""

from __future__ import annotations

import math
from collections import Counter

import numpy as np

from amr_twin.navigation.footprint import Footprint
from amr_twin.navigation.kinematics import arc_poses


class CollisionMonitor:
    """Scale or stop commands whose motion would bring the footprint to a scan return (module
    docstring)."""

    def __init__(
        self,
        footprint: Footprint,
        max_v_m_s: float,
        *,
        pad_m: float = 0.05,
        people_pad_m: float = 0.35,
        time_before_collision_s: float = 1.2,
        slow_pad_m: float = 0.9,
        slow_ratio: float = 0.4,
        step_s: float = 0.05,
        person_radius_m: float = 0.25,
        people_stop_m: float = 0.3,
        people_time_s: float = 2.0,
        people_slow_m: float = 1.2,
        people_slow_m_s: float = 0.3,
        escape_m_s: float = 0.15,
        escape_rad_s: float = 0.5,
        people_turn_m_s: float = 0.02,
        decel_m_s2: float = 1.0,
        people_stop_lag_s: float = 0.0,
    ):
        self.footprint = footprint
        near = footprint.padded(pad_m)
        side = max(pad_m, 0.1)
        # unmapped returns: the people pad ahead and behind (the way the robot drives), ``side``
        # around
        self._people = {
            1: Footprint(
                footprint.x_min_m - side,
                footprint.x_max_m + people_pad_m,
                footprint.half_width_m + side,
            ),
            -1: Footprint(
                footprint.x_min_m - people_pad_m,
                footprint.x_max_m + side,
                footprint.half_width_m + side,
            ),
            0: footprint.padded(side),
        }
        self.zones = (near, self._people[1])
        self.slow = footprint.padded(slow_pad_m)
        self.max_v_m_s = max_v_m_s
        self.time_s, self.slow_ratio, self.step_s = time_before_collision_s, slow_ratio, step_s
        self.person_radius_m, self.people_stop_m, self.people_time_s = (
            person_radius_m,
            people_stop_m,
            people_time_s,
        )
        self.decel_m_s2, self.people_stop_lag_s = decel_m_s2, people_stop_lag_s
        self.people_slow_m, self.people_slow_m_s = people_slow_m, people_slow_m_s
        self.escape_m_s, self.escape_rad_s, self.people_turn_m_s = (
            escape_m_s,
            escape_rad_s,
            people_turn_m_s,
        )
        self.actions: Counter = Counter()

    def _inside(
        self,
        points: np.ndarray,
        unmapped: np.ndarray,
        x: float = 0.0,
        y: float = 0.0,
        yaw: float = 0.0,
    ) -> int:
        """How many points lie in their zone with the robot at ``(x, y, yaw)`` of the present
        ``base_link``."""
        c, s = math.cos(yaw), math.sin(yaw)
        dx, dy = points[:, 0] - x, points[:, 1] - y
        local = np.column_stack([c * dx + s * dy, -s * dx + c * dy])
        return int(
            self.zones[0].contains(local[~unmapped]).sum()
            + self.zones[1].contains(local[unmapped]).sum()
        )

    def _time_to_collision(
        self, points: np.ndarray, unmapped: np.ndarray, v: float, w: float
    ) -> float:
        """First time (s) at which a zone, moving at (v, w) from the origin, holds a point of its
        kind."""
        n = int(math.ceil(self.time_s / self.step_s))
        poses = arc_poses(0.0, 0.0, 0.0, v, w, self.step_s, n)
        c, s = np.cos(poses[:, 2])[:, None], np.sin(poses[:, 2])[:, None]
        dx, dy = points[None, :, 0] - poses[:, 0:1], points[None, :, 1] - poses[:, 1:2]
        lx, ly = c * dx + s * dy, -s * dx + c * dy  # (n, P) in each future base_link
        hit = np.zeros(lx.shape, bool)
        for zone, which in ((self.zones[0], ~unmapped), (self.zones[1], unmapped)):
            hit |= (
                which[None, :]
                & (lx >= zone.x_min_m)
                & (lx <= zone.x_max_m)
                & (np.abs(ly) <= zone.half_width_m)
            )
        k = np.flatnonzero(hit.any(axis=1))
        return (int(k[0]) + 1) * self.step_s if len(k) else math.inf

    def _person_gap(
        self, xy: np.ndarray, x: float = 0.0, y: float = 0.0, yaw: float = 0.0
    ) -> np.ndarray:
        """Clearance (N,) from the footprint at ``(x, y, yaw)`` of ``base_link`` to people at ``xy``
        (N, 2), m."""
        c, s = math.cos(yaw), math.sin(yaw)
        dx, dy = xy[:, 0] - x, xy[:, 1] - y
        return (
            self.footprint.distance_m(np.column_stack([c * dx + s * dy, -s * dx + c * dy]))
            - self.person_radius_m
        )

    def _people_gaps(
        self, xy: np.ndarray, vel: np.ndarray, t_s: np.ndarray, poses: np.ndarray
    ) -> np.ndarray:
        """Clearance (n, N) from the footprint at each of ``poses`` (n, 3) of ``base_link`` to the
        people at ``xy`` (N, 2) walking on at ``vel`` (N, 2) for ``t_s`` (n,): :meth:`_person_gap`
        at every step at once (the same operations, so the same values; cos and sin by ``math`` as
        there)."""
        future = xy[None] + t_s[:, None, None] * vel[None]  # (n, N, 2)
        c = np.array([math.cos(a) for a in poses[:, 2]])[:, None]
        s = np.array([math.sin(a) for a in poses[:, 2]])[:, None]
        dx, dy = future[..., 0] - poses[:, 0:1], future[..., 1] - poses[:, 1:2]
        local = np.stack([c * dx + s * dy, -s * dx + c * dy], axis=-1)
        return self.footprint.distance_m(local).reshape(len(poses), -1) - self.person_radius_m

    def _people_zones(
        self, v: float, w: float, xy: np.ndarray, vel: np.ndarray
    ) -> tuple[float, float]:
        """The people zones (module docstring) for people at ``xy`` (N, 2) walking at ``vel`` (N,
        2), base_link."""
        gap = self._person_gap(xy)
        inside = gap < self.people_stop_m
        if inside.any():
            x, y, yaw = arc_poses(0.0, 0.0, 0.0, v, w, 0.2, 1)[0]
            turn_in_place = abs(v) < self.people_turn_m_s
            if (
                turn_in_place
                or (
                    self._person_gap(xy[inside] + 0.2 * vel[inside], x, y, yaw)
                    < gap[inside] - 0.005
                ).any()
            ):
                self.actions["people_stop"] += 1
                return 0.0, 0.0
            self.actions["people_escape"] += (
                1  # out of their way: at the people speed towards them, at full speed away
            )
            cap = (
                self.people_slow_m_s
                if (xy[inside, 0] * math.copysign(1.0, v) > 0.0).any()
                else self.max_v_m_s
            )
            return min(max(v, -cap), cap), min(max(w, -self.escape_rad_s), self.escape_rad_s)
        n = int(math.ceil(self.people_time_s / self.step_s))
        poses = arc_poses(0.0, 0.0, 0.0, v, w, self.step_s, n)
        t = self.step_s * np.arange(1, n + 1)
        k = np.flatnonzero(
            (self._people_gaps(xy, vel, t, poses) < self.people_stop_m + self.stopping_m(v)).any(1)
        )
        if len(k):  # the first step at which someone is within the stop clearance
            scale = t[k[0]] / self.people_time_s
            self.actions["people_approach"] += 1
            v, w = v * scale, w * scale
        towards = (xy * vel).sum(1) < 0.0  # walking towards the robot's origin
        ahead = xy[:, 0] * math.copysign(1.0, v) > 0.0 if v != 0.0 else np.zeros(len(xy), bool)
        if ((gap < self.people_slow_m) & (ahead | towards)).any() and abs(v) > self.people_slow_m_s:
            self.actions["people_slowdown"] += 1
            v = math.copysign(self.people_slow_m_s, v)
        return v, w

    def filter(
        self,
        v: float,
        w: float,
        points_base: np.ndarray,
        unmapped: np.ndarray,
        people_base: tuple[np.ndarray, np.ndarray] | None = None,
    ) -> tuple[float, float]:
        """The command ``(v, w)`` made safe against scan returns ``points_base`` (P, 2) in
        ``base_link``, of which ``unmapped`` (P,) bool the map does not hold, and against the
        tracked people ``people_base``: positions (N, 2) and velocities (N, 2) in the present
        ``base_link``."""
        if v == 0.0 and w == 0.0:
            return v, w
        if people_base is not None and len(people_base[0]):
            v, w = self._people_zones(v, w, *people_base)
            if v == 0.0 and w == 0.0:
                return v, w
        if len(points_base) == 0:
            return v, w
        self.zones = (self.zones[0], self._people[0 if abs(v) < 0.02 else (1 if v > 0 else -1)])
        reach = self.circumscribed(self.slow) + abs(v) * self.time_s + 0.1
        near = np.hypot(points_base[:, 0], points_base[:, 1]) <= reach
        pts, unmapped = points_base[near], np.asarray(unmapped, bool)[near]
        if len(pts) == 0:
            return v, w
        inside = self._inside(pts, unmapped)
        if inside:  # already too close: only moves that open the gap to the nearest return, slowly
            x, y, yaw = arc_poses(0.0, 0.0, 0.0, v, w, 0.2, 1)[0]
            c, s = math.cos(yaw), math.sin(yaw)
            dx, dy = pts[:, 0] - x, pts[:, 1] - y
            after = self.footprint.distance_m(
                np.column_stack([c * dx + s * dy, -s * dx + c * dy])
            ).min()
            if after < self.footprint.distance_m(pts).min() - 0.005:
                self.actions["stop"] += 1
                return 0.0, 0.0
            self.actions["escape"] += 1
            return self._escape(v, w)
        t_c = self._time_to_collision(pts, unmapped, v, w)
        if t_c < self.time_s:
            scale = t_c / self.time_s
            self.actions["approach"] += 1
            v, w = v * scale, w * scale
        front = pts[:, 0] * math.copysign(1.0, v) > 0.0 if v != 0.0 else np.zeros(len(pts), bool)
        if (
            v != 0.0
            and self.slow.contains(pts[front & unmapped]).any()
            and abs(v) > self.slow_ratio * self.max_v_m_s
        ):
            self.actions["slowdown"] += 1
            v = math.copysign(self.slow_ratio * self.max_v_m_s, v)
        return v, w

    def stopping_m(self, v_m_s: float) -> float:
        """How far the drive rolls after a stop at ``v_m_s``, m: ``|v| people_stop_lag_s + v^2 / (2
        decel_m_s2)`` (the drive's lag, then the ramp): the approach zone about a person grows by it
        (a protective field's stopping distance, ISO 3691-4), so that the robot stops
        ``people_stop_m`` from them."""
        v = abs(v_m_s)
        return v * self.people_stop_lag_s + v * v / (2.0 * self.decel_m_s2)

    def _escape(self, v: float, w: float) -> tuple[float, float]:
        """A move out of a zone: at most ``escape_m_s`` and ``escape_rad_s`` (a cap, not a scale: a
        scale applied to every cycle's command would shrink the ramped command to nothing)."""
        return (
            min(max(v, -self.escape_m_s), self.escape_m_s),
            min(max(w, -self.escape_rad_s), self.escape_rad_s),
        )

    @staticmethod
    def circumscribed(fp: Footprint) -> float:
        return fp.circumscribed_radius_m
