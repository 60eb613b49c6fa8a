"""Regulated Pure Pursuit, the baseline local controller (Macenski et al. 2023, nav2's RPP).

Reconstructed from the paper's description and nav2's parameter documentation, not its code:

- the carrot is the plan point ``lookahead`` of arc length ahead of the robot's progress, with
  ``lookahead = clamp(v * lookahead_time_s, min_lookahead_m, max_lookahead_m)`` (adaptive);
- pure pursuit's curvature ``kappa = 2 y / d^2`` (carrot at ``(x, y)`` in ``base_link``, distance
``d``);
- the speed is regulated: by curvature (below ``min_radius_m`` the speed scales with the turn
  radius), by proximity (closer than ``cost_scaling_dist_m`` to an obstacle it scales with the
  distance), and on approach (within ``approach_dist_m`` of the goal it scales with the remaining
  path, down to ``min_approach_v_m_s``); then the limits' ramps;
- rotate to heading: a carrot more than ``rotate_min_angle_rad`` off the robot's heading is
  turned to in place first;
- collision check: the commanded arc is projected ``collision_time_s`` ahead; if the footprint
  would touch a lethal cell the controller commands a stop and reports it (nav2 fails the
  controller; the navigator's recoveries take over).
"""

from __future__ import annotations

import math

import numpy as np

from amr_twin.navigation.costmap import Costmap
from amr_twin.navigation.footprint import Footprint
from amr_twin.navigation.interfaces import LocalController, Twist2D
from amr_twin.navigation.kinematics import Limits, arc_poses, rotation_rate, to_map
from amr_twin.navigation.path_handler import PathHandler


class RegulatedPurePursuit(LocalController):
    """nav2's Regulated Pure Pursuit (module docstring) on a :class:`Costmap`; it does not see
    people."""

    def __init__(
        self,
        costmap: Costmap,
        footprint: Footprint,
        limits: Limits,
        dt_s: float,
        *,
        lookahead_time_s: float = 1.5,
        min_lookahead_m: float = 0.4,
        max_lookahead_m: float = 1.0,
        min_radius_m: float = 0.9,
        cost_scaling_dist_m: float = 0.6,
        approach_dist_m: float = 0.8,
        min_approach_v_m_s: float = 0.1,
        rotate_min_angle_rad: float = math.radians(45.0),
        collision_time_s: float = 1.0,
    ):
        self.costmap, self.limits, self.dt_s = costmap, limits, float(dt_s)
        self.outline = footprint.outline_xy_m(0.5 * costmap.resolution_m)
        self.lookahead_time_s, self.min_lookahead_m, self.max_lookahead_m = (
            lookahead_time_s,
            min_lookahead_m,
            max_lookahead_m,
        )
        self.min_radius_m, self.cost_scaling_dist_m = min_radius_m, cost_scaling_dist_m
        self.approach_dist_m, self.min_approach_v_m_s = approach_dist_m, min_approach_v_m_s
        self.rotate_min_angle_rad, self.collision_time_s = rotate_min_angle_rad, collision_time_s
        self.rotating = False

    def carrot(self, path: PathHandler, lookahead_m: float) -> np.ndarray:
        """The plan point ``lookahead_m`` ahead of the progress (the goal beyond the end), (3,)."""
        ahead = path.ahead(lookahead_m + 0.1)
        s = path.s_m[path.index : path.index + len(ahead)] - path.s_m[path.index]
        i = min(int(np.searchsorted(s, lookahead_m)), len(ahead) - 1)
        return ahead[i] if i < len(ahead) - 1 or s[-1] >= lookahead_m else path.goal

    def collides(self, pose, v: float, w: float) -> bool:
        """Would the footprint touch a lethal cell within ``collision_time_s`` at ``(v, w)``?"""
        n = max(1, int(math.ceil(self.collision_time_s / 0.1)))
        poses = np.vstack([np.asarray(pose, float)[None], arc_poses(*pose, v, w, 0.1, n)])
        pts = to_map(poses, self.outline).reshape(-1, 2)
        return bool((self.costmap.distance_at(pts) <= 0.0).any())

    def command(self, pose, velocity, path: PathHandler, people=None, t_s: float = 0.0) -> Twist2D:
        """The twist for the robot at ``pose`` (x_m, y_m, yaw_rad) moving at ``velocity`` (v, w);
        ``people`` and ``t_s`` are not used."""
        x, y, yaw = (float(v) for v in pose)
        v_prev, w_prev = (float(v) for v in velocity)
        lim = self.limits
        lookahead = min(
            max(abs(v_prev) * self.lookahead_time_s, self.min_lookahead_m), self.max_lookahead_m
        )
        cx, cy, _ = self.carrot(path, lookahead)
        c, s = math.cos(yaw), math.sin(yaw)
        lx, ly = c * (cx - x) + s * (cy - y), -s * (cx - x) + c * (cy - y)
        alpha = math.atan2(ly, lx)
        threshold = math.radians(10.0) if self.rotating else self.rotate_min_angle_rad
        self.rotating = abs(alpha) > threshold and path.remaining_m > 0.3
        if self.rotating:
            v, w = lim.ramp(
                0.0, rotation_rate(alpha, lim, w_prev, self.dt_s), v_prev, w_prev, self.dt_s
            )
            return Twist2D(v, w, self.collides((x, y, yaw), v, w))
        d2 = max(lx * lx + ly * ly, 1e-6)
        kappa = 2.0 * ly / d2
        v = lim.max_v_m_s
        radius = 1.0 / max(abs(kappa), 1e-9)
        if radius < self.min_radius_m:
            v *= radius / self.min_radius_m
        clearance = (
            float(self.costmap.distance_at(np.array([[x, y]]))[0]) - self.costmap.inscribed_m
        )
        if clearance < self.cost_scaling_dist_m:
            v *= max(clearance, 0.0) / self.cost_scaling_dist_m
        if path.remaining_m < self.approach_dist_m:
            v *= path.remaining_m / self.approach_dist_m
        v = max(v, self.min_approach_v_m_s)
        v, _ = lim.ramp(v, 0.0, v_prev, w_prev, self.dt_s)
        w = v * kappa
        if abs(w) > lim.max_w_rad_s:  # keep the curvature: slow down instead
            v, w = v * lim.max_w_rad_s / abs(w), math.copysign(lim.max_w_rad_s, w)
        v, w = lim.ramp(v, w, v_prev, w_prev, self.dt_s)
        if self.collides((x, y, yaw), v, w):
            return Twist2D(*lim.ramp(0.0, 0.0, v_prev, w_prev, self.dt_s), True)
        return Twist2D(v, w)
