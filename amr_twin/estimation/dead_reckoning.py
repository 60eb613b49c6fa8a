"""Dead reckoning of a differential drive from wheel speed estimates (pure, no bus or clock).

The estimate of each wheel is a :class:`SpeedProfile`: a list of knots
``(t_us, rpm)``, linear between knots and held after the last. :func:`integrate`
carries a planar pose ``(x_m, y_m, yaw_rad)`` along two such profiles: exactly along
arcs (:func:`arc`) where both speeds are constant, and with arcs of at most
``max_substep_us`` at the mid-step speeds where one varies. :class:`SmoothedPose`
keeps the two profiles and the pose they imply, revised as samples arrive (the
hindsight estimate); :func:`twist_step` moves a pose by a planar twist. The profiles are
built from the firmware's speed samples (:mod:`amr_twin.controllers.wheel_speed_samples`);
the wheel odometry node (:mod:`amr_twin.controllers.odometry`) publishes a pose that
tracks the smoothed one forward in time.
"""

from __future__ import annotations

import math
from typing import Callable, Sequence

from amr_twin.estimation.drive_arcs import DriveGeometry, arc_kernel
from amr_twin.estimation.speed_profile import SpeedProfile

Pose2 = tuple[float, float, float]
"""Planar pose ``(x_m, y_m, yaw_rad)`` in ``odom`` (REP-105); yaw not wrapped."""


def arc(pose: Pose2, v_m_s: float, w_rad_s: float, dt_s: float) -> Pose2:
    """Pose after ``dt_s`` s at constant forward speed ``v_m_s`` and yaw rate ``w_rad_s``.

    Parameters
    ----------
    pose : (x_m, y_m, yaw_rad)
        Start pose.
    v_m_s, w_rad_s : float
        Forward speed of ``base_link``, m/s, and yaw rate, rad/s (CCW +).
    dt_s : float
        Duration, s.

    Returns
    -------
    (x_m, y_m, yaw_rad)
        End pose, exact on the circle (a midpoint step below 1e-9 rad of turn).
    """
    x, y, yaw0 = pose
    dyaw = w_rad_s * dt_s
    if abs(dyaw) < 1e-9:
        mid = yaw0 + 0.5 * dyaw
        return x + v_m_s * dt_s * math.cos(mid), y + v_m_s * dt_s * math.sin(mid), yaw0 + dyaw
    radius_m = v_m_s / w_rad_s
    return (
        x + radius_m * (math.sin(yaw0 + dyaw) - math.sin(yaw0)),
        y - radius_m * (math.cos(yaw0 + dyaw) - math.cos(yaw0)),
        yaw0 + dyaw,
    )


def integrate(
    profiles: Sequence[SpeedProfile],
    start: tuple,
    t_end_us: int,
    max_substep_us: int,
    body: Callable[[float, float], tuple[float, float]],
    native: bool = True,
) -> tuple:
    """Pose ``(t_us, x_m, y_m, yaw_rad)`` at ``t_end_us`` from ``start`` along the speed profiles.

    Parameters
    ----------
    profiles : sequence of 2 SpeedProfile
        Left and right wheel speed estimates, RPM.
    start : (t_us, x_m, y_m, yaw_rad)
        Start instant, us, and pose.
    t_end_us : int
        End instant, us (at or after ``start[0]``).
    max_substep_us : int
        Longest arc while a speed varies, us (> 0).
    body : callable ``(left_rpm, right_rpm) -> (v_m_s, w_rad_s)``
        Wheel speeds to the body twist (the drive geometry).
    native : bool
        With a :class:`~amr_twin.estimation.drive_arcs.DriveGeometry` body, run the C twin
        (:mod:`amr_twin.estimation.drive_arcs`, same bits) when it builds.

    Returns
    -------
    (t_end_us, x_m, y_m, yaw_rad)
    """
    if native and type(body) is DriveGeometry and (kernel := arc_kernel()) is not None:
        return kernel.integrate(profiles, start, t_end_us, max_substep_us, body)
    t, pose = start[0], start[1:]
    knots = sorted({k for p in profiles for k in p.t_us if t < k < t_end_us})
    for t_next in knots + [t_end_us]:
        if t_next <= t:
            continue
        segs = [p.segment(t) for p in profiles]
        ends = [p.at(t_next, s) for p, s in zip(profiles, segs)]
        starts = [p.at(t, s) for p, s in zip(profiles, segs)]
        n = 1 if starts == ends else -(-(t_next - t) // max_substep_us)
        dt_us = (t_next - t) / n
        dt_s = dt_us * 1e-6
        (ta, ra, tb, rb), (tc, rc, td, rd) = (
            segs  # SpeedProfile.at on them, spelled out (up to 50 a call)
        )
        rise_l, span_l, rise_r, span_r = rb - ra, tb - ta, rd - rc, td - tc
        for k in range(n):
            mid = t + (k + 0.5) * dt_us
            left = ra if tb <= ta else ra + rise_l * (mid - ta) / span_l
            right = rc if td <= tc else rc + rise_r * (mid - tc) / span_r
            pose = arc(pose, *body(left, right), dt_s)
        t = t_next
    return (t_end_us, *pose)


def twist_step(pose: Pose2, vx_m_s: float, vy_m_s: float, w_rad_s: float, dt_s: float) -> Pose2:
    """Pose after ``dt_s`` s at the constant body twist ``(vx, vy, w)`` (SE(2) exponential)."""
    x, y, yaw = pose
    th = w_rad_s * dt_s
    if abs(th) < 1e-9:
        a, b = dt_s, 0.5 * th * dt_s
    else:
        a, b = math.sin(th) / w_rad_s, (1.0 - math.cos(th)) / w_rad_s
    dx, dy = a * vx_m_s - b * vy_m_s, b * vx_m_s + a * vy_m_s  # body frame at the start
    c, s = math.cos(yaw), math.sin(yaw)
    return x + c * dx - s * dy, y + s * dx + c * dy, yaw + th


class SmoothedPose:
    """Both wheels' speed profiles and the pose they imply, revised when samples arrive.

    The profiles are changed by the caller (samples, brake ramps); :meth:`changed`
    marks them so. :meth:`pose_at` integrates from an *anchor*, the pose at the
    last instant no later sample can change (the last knot at or before now of
    each wheel), so a sample that describes the past moves the pose after it: the
    best estimate in hindsight, not a continuous one.

    Parameters
    ----------
    t_us : int
        Start instant, us.
    pose : (x_m, y_m, yaw_rad)
        Start pose.
    rpm : (left, right)
        Speeds in force at the start, RPM.
    body : callable ``(left_rpm, right_rpm) -> (v_m_s, w_rad_s)``
        The drive geometry.
    max_substep_us : int
        Longest arc while a speed varies, us.
    """

    def __init__(
        self,
        t_us: int,
        pose: Pose2,
        rpm: Sequence[float],
        body: Callable[[float, float], tuple[float, float]],
        max_substep_us: int,
    ):
        self.profiles = [SpeedProfile(t_us, rpm[0]), SpeedProfile(t_us, rpm[1])]
        self.body, self.max_substep_us = body, max_substep_us
        self._anchor = (t_us, *pose)  # final: no sample can change the pose before it
        self._cache = self._anchor  # pose at the newest knot of either wheel (up to now)
        self._hold = None  # (v, w) when both speeds are held from the cache on ...
        self._hold_until_us = self._anchor[0]  # ... up to this instant
        self._dirty = False

    def changed(self) -> None:
        """The profiles were changed: recompute the pose at the next :meth:`pose_at`."""
        self._dirty = True

    def speeds_rpm(self, t_us: float) -> list[float]:
        """Both wheels' estimated speeds at ``t_us``, RPM."""
        return [p.at(t_us, p.segment(t_us)) for p in self.profiles]

    def _steady(self, t_us: int) -> tuple[tuple[float, float] | None, float]:
        """Body twist (m/s, rad/s) both speeds hold from ``t_us`` to the instant returned (us,
        ``inf``: the last knot), with the speeds :func:`integrate` uses there; ``None`` if one
        varies."""
        until, rpm = math.inf, []
        for p in self.profiles:
            seg = p.segment(t_us)
            t0, r0, t1, r1 = seg
            if t0 > t_us or (t1 > t0 and r1 != r0):
                return None, t_us
            if t1 > t0:  # constant piece up to its end: integrate's speed at a mid-step instant
                until = min(until, t1)
            rpm.append(p.at(t1, seg))
        return self.body(*rpm), until

    def pose_at(self, now_us: int) -> Pose2:
        """The pose at ``now_us`` (not before the previous call's instant), yaw unwrapped."""
        if self._dirty:
            # final up to the last knot at or before now of each wheel: later samples are
            # clipped there (knots after now are assumptions, e.g. a brake ramp)
            horizon = min(p.known_us(now_us) for p in self.profiles)
            if horizon > self._anchor[0]:
                self._anchor = integrate(
                    self.profiles, self._anchor, horizon, self.max_substep_us, self.body
                )
                for p in self.profiles:
                    p.trim(horizon)
            newest = min(max(p.last_us for p in self.profiles), now_us)
            self._cache = integrate(
                self.profiles,
                self._anchor,
                max(newest, self._anchor[0]),
                self.max_substep_us,
                self.body,
            )
            self._dirty = False
            self._hold, self._hold_until_us = self._steady(self._cache[0])
        cache, hold = self._cache, self._hold
        if now_us <= cache[0]:
            return cache[1:]
        if (
            hold is not None and now_us <= self._hold_until_us
        ):  # one arc: what integrate computes, cheaper
            return arc(cache[1:], hold[0], hold[1], float(now_us - cache[0]) * 1e-6)
        return tuple(integrate(self.profiles, cache, now_us, self.max_substep_us, self.body)[1:])
