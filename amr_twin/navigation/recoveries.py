"""The recoveries of nav2's default behaviour tree: clear the costmaps, spin, wait, back up.

Each is a small state machine: :meth:`start` it at the robot's pose, then call :meth:`step`
every control cycle for a twist until it reports done (or failed). Spin and back-up check the
footprint against the costmap before each step (nav2 checks ``simulate_ahead_time`` ahead) and
stop, failed, rather than hit something: a recovery must not be the cause of a collision. They are
registered by name in :data:`~amr_twin.navigation.registries.RECOVERIES`, where
:data:`~amr_twin.navigation.registries.ROUND_ROBIN` is the order nav2's ``RoundRobin`` node runs
them in."""

from __future__ import annotations

import math

import numpy as np

from amr_twin.navigation.costmap import Costmap
from amr_twin.navigation.footprint import Footprint
from amr_twin.navigation.interfaces import RecoveryBehaviour, Step
from amr_twin.navigation.kinematics import Limits, arc_poses, rotation_rate, to_map, wrap


class Recovery(RecoveryBehaviour):
    """Base: a behaviour on a costmap, with the robot's footprint and limits."""

    def __init__(
        self, costmap: Costmap, footprint: Footprint, limits: Limits, dt_s: float, **settings
    ):
        """``settings``: the class's own (``angle_rad``, ``duration_s``, ``distance_m``,
        ``speed_m_s``) for this one."""
        for key, value in settings.items():
            if not hasattr(type(self), key):
                raise TypeError(f"{type(self).__name__}: no setting {key!r}")
            setattr(self, key, value)
        self.costmap, self.limits, self.dt_s = costmap, limits, dt_s
        self.outline = footprint.outline_xy_m(0.5 * costmap.resolution_m)
        self.t0_s, self.pose0 = 0.0, np.zeros(3)

    def start(self, t_s: float, pose) -> None:
        self.t0_s, self.pose0 = t_s, np.asarray(pose, float).copy()

    def free(self, poses: np.ndarray) -> bool:
        """No footprint of ``poses`` (n, 3) touches a lethal cell."""
        return bool(
            (self.costmap.distance_at(to_map(poses, self.outline).reshape(-1, 2)) > 0.0).all()
        )

    def step(self, t_s: float, pose, velocity) -> Step:
        raise NotImplementedError


class ClearCostmaps(Recovery):
    """nav2's ClearEntireCostmap (local and global): the obstacle layer forgotten, at once."""

    def step(self, t_s, pose, velocity) -> Step:
        self.costmap.clear()
        return Step(done=True)


class Spin(Recovery):
    """nav2's Spin: turn in place by ``angle_rad`` (counter-clockwise), checking the footprint
    ahead."""

    angle_rad = math.pi / 2

    def step(self, t_s, pose, velocity) -> Step:
        turned = float(wrap(pose[2] - self.pose0[2]))
        left = self.angle_rad - (turned if turned > -0.5 else turned + 2 * math.pi)
        if left <= 0.05 or t_s - self.t0_s > 10.0:
            return Step(*self.limits.ramp(0.0, 0.0, *velocity, self.dt_s), done=True)
        w = rotation_rate(left, self.limits, velocity[1], self.dt_s)
        ahead = np.column_stack(
            [np.full(5, pose[0]), np.full(5, pose[1]), pose[2] + np.linspace(0.1, 0.4, 5)]
        )
        if not self.free(ahead):
            return Step(done=True, failed=True)
        return Step(*self.limits.ramp(0.0, w, *velocity, self.dt_s))


class Wait(Recovery):
    """nav2's Wait: stand for ``duration_s`` (a person may walk on)."""

    duration_s = 5.0

    def step(self, t_s, pose, velocity) -> Step:
        v, w = self.limits.ramp(0.0, 0.0, *velocity, self.dt_s)
        return Step(v, w, done=t_s - self.t0_s >= self.duration_s)


class BackUp(Recovery):
    """nav2's BackUp: reverse ``distance_m`` at ``speed_m_s``, checking the footprint behind."""

    distance_m, speed_m_s = 0.3, 0.1

    def step(self, t_s, pose, velocity) -> Step:
        gone = math.hypot(pose[0] - self.pose0[0], pose[1] - self.pose0[1])
        if gone >= self.distance_m or t_s - self.t0_s > 3 * self.distance_m / self.speed_m_s:
            return Step(*self.limits.ramp(0.0, 0.0, *velocity, self.dt_s), done=True)
        if not self.free(arc_poses(*pose, -self.speed_m_s, 0.0, 0.1, 10)):
            return Step(*self.limits.ramp(0.0, 0.0, *velocity, self.dt_s), done=True, failed=True)
        return Step(*self.limits.ramp(-self.speed_m_s, 0.0, *velocity, self.dt_s))
