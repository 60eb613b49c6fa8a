"""The pose the wheel odometry node publishes (REP-105: ``odom -> base_link`` must be continuous).

The *smoothed* pose (:class:`~amr_twin.estimation.dead_reckoning.SmoothedPose`)
integrates the wheels' speed estimates, and a window that arrives corrects the past it
describes: the best estimate in hindsight, which jumps when a sample arrives
(0.7 m after the first revolution of a start). The *published* pose is integrated
forward only, as a ROS diff-drive controller does, and never revised: it moves
with the wheel speeds in force (each following its estimate at most at
``max_wheel_accel_m_s2``: the two wheels' samples arrive at different instants),
plus a correction twist that makes up its difference to the smoothed pose, in the
body frame, over one time ``T >= catchup_time_s`` for x, y and yaw together,
stretched so that the correction stays within ``catchup_max_fraction`` of the
motion the wheels give (of the speed for x and y; for yaw, of the larger of the yaw rate and the one
either wheel's speed gives turning in place, so a heading seen late is made up before a stop) plus
:data:`CATCHUP_FLOOR_M_S` and :data:`CATCHUP_FLOOR_RAD_S` (what is left at a stop settles at those
rates). The published twist is the one the published pose moves with, correction included
(``linear.y`` is non-zero only while a sideways difference is made up), so integrating it gives the
pose."""

from __future__ import annotations

import math
from typing import Callable, Sequence

from amr_twin.estimation.dead_reckoning import SmoothedPose, arc, twist_step
from amr_twin.estimation.drive_arcs import DriveGeometry, arc_kernel

DEADBAND_M, DEADBAND_RAD = 5e-4, 5e-4
"""A difference to the smoothed pose below both is left alone, m and rad (the correction ends)."""
CATCHUP_FLOOR_M_S, CATCHUP_FLOOR_RAD_S = 0.05, 0.1
"""Correction allowed beyond ``catchup_max_fraction`` of the wheels' motion (the rest after a stop),
m/s, rad/s."""


class PublishedPose:
    """The published pose and the smoothed pose it follows, on the virtual clock's microseconds.

    Parameters
    ----------
    body : callable
        ``(left_rpm, right_rpm) -> (v_m_s, w_rad_s)``: the body's forward speed and yaw
        rate (CCW +) from signed wheel speeds in RPM.
    max_substep_us : int
        Longest arc while a speed varies, us.
    accel_rpm_per_us : (float, float)
        Fastest change of the left and right speed the published pose moves with, RPM/us
        (``inf``: none).
    catchup_s : float
        Shortest time over which the difference to the smoothed pose is made up, s (> 0).
    catchup_max_fraction : float
        Largest correction as a fraction of the wheels' speed and yaw rate (>= 0), beyond the
        floors.
    native : bool
        With a :class:`~amr_twin.estimation.drive_arcs.DriveGeometry` body, integrate forward in
        C (:mod:`amr_twin.estimation.drive_arcs`, same bits) when the helper builds.

    Call :meth:`restart` before use.
    """

    def __init__(
        self,
        body: Callable[[float, float], tuple[float, float]],
        max_substep_us: int,
        accel_rpm_per_us: tuple[float, float],
        catchup_s: float,
        catchup_max_fraction: float,
        native: bool = True,
    ):
        self._body, self.max_substep_us = body, max_substep_us
        self._kernel = arc_kernel() if native and type(body) is DriveGeometry else None
        self.accel_rpm_per_us = accel_rpm_per_us
        self.catchup_s, self.catchup_max_fraction = catchup_s, catchup_max_fraction

    def restart(self, t_us: int, pose: tuple[float, float, float], rpm: Sequence[float]) -> None:
        """Both poses at ``pose`` (``x_m, y_m, yaw_rad``) at ``t_us``, the wheels at ``rpm`` (left,
        right)."""
        self.smoothed = SmoothedPose(t_us, pose, rpm, self._body, self.max_substep_us)
        self.profiles = self.smoothed.profiles
        self.t_us = t_us  # the published pose is integrated up to here; never revised
        self.pose = tuple(float(v) for v in pose)  # x_m, y_m, yaw_rad; yaw not wrapped
        self.used = [float(rpm[0]), float(rpm[1])]  # RPM the pose moves with at self.t_us
        self.correction = (0.0, 0.0, 0.0)  # body twist toward the smoothed pose: m/s, m/s, rad/s

    def changed(self) -> None:
        """The speed profiles changed: recompute the smoothed pose and the correction."""
        self.smoothed.changed()
        if self.accel_rpm_per_us[0] == math.inf:  # no limit: a new speed is in force at once
            self.used = self.smoothed.speeds_rpm(self.t_us)
        self.retarget()

    def retarget(self) -> None:
        """The correction twist from the difference between the smoothed and the published pose
        now."""
        x, y, yaw = self.pose
        hx, hy, hyaw = self.smoothed.pose_at(self.t_us)
        c, s = math.cos(yaw), math.sin(yaw)
        ex, ey = c * (hx - x) + s * (hy - y), -s * (hx - x) + c * (hy - y)
        eyaw = hyaw - yaw  # both unwrapped from the same start: no wrapping (a spin can lag > pi)
        e_xy = math.hypot(ex, ey)
        if e_xy <= DEADBAND_M and abs(eyaw) <= DEADBAND_RAD:
            self.correction = (0.0, 0.0, 0.0)
            return
        v, w = self._body(*self.used)
        k = self.catchup_max_fraction
        # yaw: within the fraction of the yaw rate, or of the one the wheels' speed gives turning in
        # place
        w_wheels = max(
            abs(w),
            abs(self._body(-self.used[0], self.used[0])[1]),
            abs(self._body(self.used[1], -self.used[1])[1]),
        )
        t_s = max(
            self.catchup_s,
            e_xy / (k * abs(v) + CATCHUP_FLOOR_M_S),
            abs(eyaw) / (k * w_wheels + CATCHUP_FLOOR_RAD_S),
        )
        self.correction = (ex / t_s, ey / t_s, eyaw / t_s)

    def twist(self) -> tuple[float, float, float]:
        """Body twist the published pose moves with at :attr:`t_us`: ``vx_m_s, vy_m_s, w_rad_s``
        (CCW +)."""
        v, w = self._body(*self.used)
        cx, cy, cw = self.correction
        return v + cx, cy, w + cw

    def advance(self, now_us: int) -> None:
        """Integrate the published pose forward from :attr:`t_us` to ``now_us``.

        Pieces between the speed profiles' knots; within a piece steps of at most
        ``max_substep_us`` while a speed varies (one exact arc when none does and no
        correction runs). The correction twist stays as computed at the previous
        update; it is recomputed at the end.
        """
        now = now_us
        t = self.t_us
        if now <= t:
            return
        profiles, used, accel = self.profiles, self.used, self.accel_rpm_per_us
        if self._kernel is not None:
            self.pose = self._kernel.advance(
                profiles,
                t,
                now,
                self.pose,
                used,
                accel,
                self.correction,
                self.max_substep_us,
                self._body,
            )
            self.t_us = now
            self.retarget()
            return
        cx, cy, cw = self.correction
        steady = cx == cy == cw == 0.0
        pose = self.pose
        knots = sorted({k for p in profiles for k in p.t_us if t < k < now})
        for t_next in knots + [now]:
            segs = [p.segment(t) for p in profiles]
            while t < t_next:
                if steady:
                    rpm0 = [p.at(t, sg) for p, sg in zip(profiles, segs)]
                    if rpm0 == used and [p.at(t_next, sg) for p, sg in zip(profiles, segs)] == rpm0:
                        pose = arc(pose, *self._body(*used), (t_next - t) * 1e-6)  # exact
                        t = t_next
                        continue
                t1 = min(t_next, t + self.max_substep_us)
                dt = t1 - t
                mean = [0.0, 0.0]
                for w in (0, 1):
                    s0, r0, s1, r1 = segs[
                        w
                    ]  # SpeedProfile.at(t1, segs[w]), spelled out (it runs at 100 Hz)
                    goal = r0 if s1 <= s0 else r0 + (r1 - r0) * (t1 - s0) / (s1 - s0)
                    step = accel[w] * dt
                    new = min(max(goal, used[w] - step), used[w] + step)
                    mean[w] = 0.5 * (used[w] + new)
                    used[w] = new
                v, w_rad_s = self._body(*mean)
                pose = twist_step(pose, v + cx, cy, w_rad_s + cw, dt * 1e-6)
                t = t1
        self.t_us, self.pose = now, pose
        self.retarget()
