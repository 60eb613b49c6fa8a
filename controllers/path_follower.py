"""A pure-pursuit path follower publishing ``geometry_msgs/Twist`` on ``cmd_vel``.

Routes (:mod:`.route`, re-exported here) are polylines in the ``map`` frame.

Reasons and measurements: docs/explanation/navigation.md#amr_twincontrollerspath_follower."""

from __future__ import annotations

import math
from typing import Callable

import numpy as np

from amr_twin.ros.bus import Bus
from amr_twin.base.clock import VirtualClock
from amr_twin.ros.geometry_messages import Twist, Vector3

from amr_twin.controllers.route import Route


class PurePursuit:
    """Pure-pursuit follower of a :class:`Route` (pure logic, no clock, no bus).

    Parameters
    ----------
    route : Route
    min_speed_m_s : float
        Floor of the linear speed while driving, m/s (the firmware cannot hold a crawl).
    decel_m_s2 : float
        Deceleration of the stop at the goal, m/s^2.
    turn_in_place_rad, turn_in_place_exit_rad : float
        Bearing of the lookahead point above which the robot turns in place, and
        below which it drives again, rad.
    turn_gain_per_s : float
        Yaw rate per rad of bearing in a turn in place, 1/s (clipped to the route's limit).
    sharp_corner_rad : float
        Corners turning by more than this are approached slowing down to the least speed, rad.
    """

    def __init__(
        self,
        route: Route,
        *,
        min_speed_m_s: float = 0.1,
        decel_m_s2: float = 0.5,
        turn_in_place_rad: float = math.radians(60.0),
        turn_in_place_exit_rad: float = math.radians(20.0),
        turn_gain_per_s: float = 1.5,
        sharp_corner_rad: float = math.radians(120.0),
    ):
        self.route = route
        self.path = route.path_xy_m()
        self._seg = seg = np.diff(self.path, axis=0)
        self._seg_len = np.hypot(seg[:, 0], seg[:, 1])
        self._s0 = np.concatenate([[0.0], np.cumsum(self._seg_len)])  # arc length at each vertex
        self.length_m = float(self._s0[-1])
        self.min_speed_m_s = min(float(min_speed_m_s), route.max_speed_m_s)
        self.decel_m_s2 = float(decel_m_s2)
        self.turn_in_place_rad, self.turn_in_place_exit_rad = (
            float(turn_in_place_rad),
            float(turn_in_place_exit_rad),
        )
        self.turn_gain_per_s = float(turn_gain_per_s)
        self.search_m = 2.0 * route.lookahead_m + 1.0
        turn = np.abs(
            np.angle(np.exp(1j * np.diff(np.arctan2(seg[:, 1], seg[:, 0]))))
        )  # at interior vertices
        self._sharp_s = self._s0[1:-1][turn > float(sharp_corner_rad)]
        """Arc lengths of the corners the robot will turn in place at, m."""
        self.progress_m = 0.0
        """Arc length of the robot's projection on the path, m (never decreases)."""
        self.cross_track_m = 0.0
        """Distance from the robot to its projection at the last command, m."""
        self.lookahead_xy_m = self.path[min(1, len(self.path) - 1)].copy()
        self.turning_in_place = False
        self.done = False

    def point_at(self, s_m: float) -> np.ndarray:
        """Path point ``(2,)`` at arc length ``s_m`` (clamped to the path), m."""
        s = min(max(s_m, 0.0), self.length_m)
        i = min(int(np.searchsorted(self._s0, s, side="right")) - 1, len(self._seg) - 1)
        return self.path[i] + self._seg[i] * ((s - self._s0[i]) / self._seg_len[i])

    def _project(self, xy: np.ndarray) -> tuple[float, float]:
        """Arc length and distance of the nearest path point in ``[progress, progress +
        search]``."""
        lo, hi = self.progress_m, self.progress_m + self.search_m
        n = len(self._seg)
        first = min(max(int(np.searchsorted(self._s0, lo, side="right")) - 1, 0), n - 1)
        last = max(min(int(np.searchsorted(self._s0, hi, side="right")), n), first + 1)
        a, ab, s0, length = (
            self.path[first:last],
            self._seg[first:last],
            self._s0[first:last],
            self._seg_len[first:last],
        )
        u = ((xy - a) * ab).sum(1) / (length * length)
        u = np.minimum(
            np.maximum(u, np.maximum((lo - s0) / length, 0.0)), np.minimum((hi - s0) / length, 1.0)
        )
        dist = np.hypot(*(a + u[:, None] * ab - xy).T)
        k = int(
            np.argmax(dist <= dist.min() + 1e-6)
        )  # the nearest; of a path doubling back, the earlier leg
        return float(s0[k] + u[k] * length[k]), float(dist[k])

    def command(self, x_m: float, y_m: float, yaw_rad: float) -> tuple[float, float, bool]:
        """Twist for the robot at ``(x_m, y_m, yaw_rad)`` in ``map``: ``(linear_m_s, angular_rad_s,
        done)``."""
        if not all(math.isfinite(v) for v in (x_m, y_m, yaw_rad)):
            raise ValueError(f"pose: ({x_m}, {y_m}, {yaw_rad}) must be finite (x_m, y_m, yaw_rad)")
        if self.done:
            return 0.0, 0.0, True
        r = self.route
        xy = np.array([x_m, y_m], dtype=float)
        s, self.cross_track_m = self._project(xy)
        self.progress_m = max(self.progress_m, s)
        goal = self.path[-1]
        remaining_m = self.length_m - self.progress_m
        if (
            math.hypot(*(goal - xy)) <= r.goal_tolerance_m
            and remaining_m <= r.lookahead_m + r.goal_tolerance_m
        ):
            self.done = True
            return 0.0, 0.0, True
        target = self.point_at(self.progress_m + r.lookahead_m)
        self.lookahead_xy_m = target
        dx, dy = target - xy
        c, s_ = math.cos(yaw_rad), math.sin(yaw_rad)
        lx, ly = c * dx + s_ * dy, -s_ * dx + c * dy  # lookahead point in base_link
        alpha = math.atan2(ly, lx)
        dist = max(math.hypot(lx, ly), 1e-6)
        threshold = self.turn_in_place_exit_rad if self.turning_in_place else self.turn_in_place_rad
        self.turning_in_place = abs(alpha) > threshold
        if self.turning_in_place:
            w = max(-r.max_angular_rad_s, min(r.max_angular_rad_s, self.turn_gain_per_s * alpha))
            return 0.0, w, False
        curvature = 2.0 * math.sin(alpha) / dist
        ahead = self._sharp_s[self._sharp_s > self.progress_m - 1e-9]
        to_stop_m = (
            min(remaining_m, float(ahead[0]) - self.progress_m - 0.5 * r.lookahead_m)
            if ahead.size
            else remaining_m
        )
        v = min(r.max_speed_m_s, math.sqrt(2.0 * self.decel_m_s2 * max(to_stop_m, 0.0)))
        if abs(curvature) > 1e-9:
            v = min(v, r.max_angular_rad_s / abs(curvature))
        v = max(v, self.min_speed_m_s)
        w = max(-r.max_angular_rad_s, min(r.max_angular_rad_s, v * curvature))
        return v, w, False


class PathFollowerNode:
    """Publish the pure-pursuit twist of a route on ``cmd_vel`` at ``rate_hz`` on the clock.

    Parameters
    ----------
    bus, clock : Bus, VirtualClock
    route : Route
    pose_source : callable
        ``pose_source() -> (x_m, y_m, yaw_rad)`` of ``base_link`` in ``map`` (e.g. the true pose).
    rate_hz : float
        Command rate, Hz (> 0).
    topic : str
        Output topic.
    **pursuit
        Keyword arguments of :class:`PurePursuit`.

    Once the route is done the node keeps publishing a zero twist (the diff-drive
    node brakes once and is kept from timing out) until :meth:`shutdown`.
    ``history()`` returns what was commanded.
    """

    def __init__(
        self,
        bus: Bus,
        clock: VirtualClock,
        route: Route,
        pose_source: Callable[[], tuple[float, float, float]],
        rate_hz: float = 20.0,
        topic: str = "cmd_vel",
        **pursuit,
    ):
        if not (math.isfinite(rate_hz) and rate_hz > 0):
            raise ValueError(f"rate_hz: {rate_hz} must be a finite number > 0")
        self.bus, self.clock, self.route = bus, clock, route
        self.pursuit = PurePursuit(route, **pursuit)
        self.pose_source = pose_source
        self.period_us = max(1, int(round(1e6 / rate_hz)))
        self._pub = bus.advertise(topic, Twist)
        self._rows: list[tuple[float, float, float, float, float]] = []
        self._timer = clock.schedule_in(0, self._on_timer)

    @property
    def done(self) -> bool:
        """True once the goal is reached."""
        return self.pursuit.done

    def _on_timer(self) -> None:
        self._timer = self.clock.schedule_in(self.period_us, self._on_timer)
        x_m, y_m, yaw_rad = self.pose_source()
        v, w, _ = self.pursuit.command(x_m, y_m, yaw_rad)
        self._rows.append(
            (self.clock.now_us * 1e-6, v, w, self.pursuit.cross_track_m, self.pursuit.progress_m)
        )
        self._pub.publish(Twist(Vector3(v, 0.0, 0.0), Vector3(0.0, 0.0, w)))

    def history(self) -> dict[str, np.ndarray]:
        """Commands so far: ``t_s``, ``linear_m_s``, ``angular_rad_s``, ``cross_track_m``,
        ``progress_m`` (each (K,))."""
        rows = np.array(self._rows, dtype=float).reshape(-1, 5)
        return dict(
            zip(("t_s", "linear_m_s", "angular_rad_s", "cross_track_m", "progress_m"), rows.T)
        )

    def shutdown(self) -> None:
        """Stop publishing."""
        self._timer.cancel()
