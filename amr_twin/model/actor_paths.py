"""An actor's path in time: phases of constant velocity and constant turn rate.

:func:`actor_path` turns an :class:`~amr_twin.model.actors.Actor` into a table of phases, each
row ``t0_s, x0_m, y0_m, vx_m_s, vy_m_s, yaw0_rad, yaw_rate_rad_s``: from its start ``t0_s``
(seconds of walking, counted from the actor's ``start_s``) to the next row's, the actor is at
``x0 + (t - t0) vx``, ``y0 + (t - t0) vy`` heading ``yaw0 + (t - t0) yaw_rate``. A segment is a
move at ``speed_m_s`` along its direction (heading along it); a corner a turn on the spot by the
smaller angle to the next segment's heading at the kind's ``turn_rate_rad_s``; the first
segment starts already facing along it. Without ``loop`` a last row holds the actor at its last
waypoint; with it the path closes back to the first waypoint, turns to the first heading, and
repeats every :attr:`ActorPath.period_s`.

:meth:`ActorPath.pose_at` is the Python twin of ``actors.c``'s ``actor_pose``
(:mod:`amr_twin.sim.actors`): the same operations in the same order (``fmod``, the phase
search, one multiply-add per value with fused multiply-adds off), so both give the same bits.
"""

from __future__ import annotations

import bisect
import math
from dataclasses import dataclass

import numpy as np

COLUMNS = ("t0_s", "x0_m", "y0_m", "vx_m_s", "vy_m_s", "yaw0_rad", "yaw_rate_rad_s")


def wrap_rad(a: float) -> float:
    """``a`` wrapped into (-pi, pi], rad."""
    a = math.remainder(a, 2 * math.pi)
    return math.pi if a == -math.pi else a


@dataclass(frozen=True)
class ActorPath:
    """Phases (n, 7) float64 (:data:`COLUMNS`) and the loop period (0: no loop), s."""

    phases: np.ndarray
    period_s: float

    def __post_init__(self) -> None:
        rows = self.phases.tolist()  # plain floats: a pose costs a few us, at every grid instant
        object.__setattr__(self, "_rows", rows)
        object.__setattr__(self, "_t0", [r[0] for r in rows])

    def pose_at(self, t_s: float) -> tuple[float, float, float]:
        """``(x_m, y_m, yaw_rad)`` after ``t_s`` seconds of walking (>= 0)."""
        if self.period_s > 0.0:
            t_s = math.fmod(t_s, self.period_s)
        j = max(bisect.bisect_right(self._t0, t_s) - 1, 0)
        t0, x0, y0, vx, vy, yaw0, rate = self._rows[j]
        dt = t_s - t0
        return x0 + dt * vx, y0 + dt * vy, yaw0 + dt * rate

    @property
    def duration_s(self) -> float:
        """Walking time of one pass (to the last waypoint, or round the loop), s."""
        return self.period_s if self.period_s > 0 else float(self.phases[-1, 0])


def actor_path(actor, cfg) -> ActorPath:
    """The phases of ``actor`` (an :class:`~amr_twin.model.actors.Actor`) with its kind's turn rate
    from ``cfg.actors`` (module notes)."""
    rate = getattr(cfg.actors, actor.kind).turn_rate_rad_s
    points = list(actor.waypoints_xy_m)
    if actor.loop and points[-1] != points[0]:
        points.append(points[0])
    segments = [(a, b) for a, b in zip(points[:-1], points[1:])]
    rows: list[tuple[float, ...]] = []
    t = 0.0
    if not segments:  # one waypoint: standing, facing +x
        x, y = points[0]
        return ActorPath(np.array([[0.0, x, y, 0.0, 0.0, 0.0, 0.0]]), 0.0)
    yaw = math.atan2(segments[0][1][1] - segments[0][0][1], segments[0][1][0] - segments[0][0][0])

    def turn(x: float, y: float, heading: float) -> None:
        nonlocal t, yaw
        delta = wrap_rad(heading - yaw)
        if delta != 0.0:
            rows.append((t, x, y, 0.0, 0.0, yaw, math.copysign(rate, delta)))
            t += abs(delta) / rate
        yaw = wrap_rad(heading)

    for (x0, y0), (x1, y1) in segments:
        dx, dy = x1 - x0, y1 - y0
        length = math.hypot(dx, dy)
        turn(x0, y0, math.atan2(dy, dx))
        rows.append(
            (t, x0, y0, actor.speed_m_s * dx / length, actor.speed_m_s * dy / length, yaw, 0.0)
        )
        t += length / actor.speed_m_s
    x_end, y_end = points[-1]
    if actor.loop:
        first = rows[0][5]
        turn(x_end, y_end, first)
        return ActorPath(np.array(rows), t)
    rows.append((t, x_end, y_end, 0.0, 0.0, yaw, 0.0))
    return ActorPath(np.array(rows), 0.0)
