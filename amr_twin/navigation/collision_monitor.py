"""The collision monitor on raw scans (nav2's collision_monitor): approach and slowdown zones.

It sits between the controller and the drive (``cmd_vel_nav`` -> ``cmd_vel`` in nav2), looks at
the latest scan's returns in ``base_link`` (not at the costmap: it guards against whatever the
planner and controller missed), and changes a command only to make it safer. Each return is
either *mapped* (within a few cm of the static map: a rack, a wall) or *unmapped* (a person, a
pallet jack); the caller says which. Zones are the footprint grown by a pad:

- *approach*: the command is projected ``time_before_collision_s`` ahead; if the footprint grown
  by ``pad_m`` (mapped returns) or, for unmapped ones, by ``people_pad_m`` at its front (its rear
  when backing up; the clearance kept from people) and 0.1 m elsewhere (a turn in place) would reach a return within that time, the speeds are scaled so that it would reach it no earlier
  than ``time_before_collision_s`` (nav2's approach model); a return already inside the grown
  footprint stops the robot unless the command opens the gap to the nearest return (then slowly);
- *slowdown*: an unmapped return inside the footprint grown by ``slow_pad_m`` ahead of the robot
  (in the direction of travel) caps the linear speed at ``slow_ratio`` of the limit.

Every action is counted in :attr:`CollisionMonitor.actions`.
"""

from __future__ import annotations

import math
from collections import Counter

import numpy as np

from amr_twin.navigation.footprint import Footprint
from amr_twin.navigation.kinematics import arc_poses


class CollisionMonitor:
    """Scale or stop commands whose motion would bring the footprint to a scan return (module docstring)."""

    def __init__(self, footprint: Footprint, max_v_m_s: float, *, pad_m: float = 0.05, people_pad_m: float = 0.35,
                 time_before_collision_s: float = 1.2, slow_pad_m: float = 0.9, slow_ratio: float = 0.4,
                 step_s: float = 0.05):
        self.footprint = footprint
        near = footprint.padded(pad_m)
        side = max(pad_m, 0.1)
        # unmapped returns: the people pad ahead and behind (the way the robot drives), ``side`` around
        self._people = {1: Footprint(footprint.x_min_m - side, footprint.x_max_m + people_pad_m, footprint.half_width_m + side),
                        -1: Footprint(footprint.x_min_m - people_pad_m, footprint.x_max_m + side, footprint.half_width_m + side),
                        0: footprint.padded(side)}
        self.zones = (near, self._people[1])
        self.slow = footprint.padded(slow_pad_m)
        self.max_v_m_s = max_v_m_s
        self.time_s, self.slow_ratio, self.step_s = time_before_collision_s, slow_ratio, step_s
        self.actions: Counter = Counter()

    def _inside(self, points: np.ndarray, unmapped: np.ndarray, x: float = 0.0, y: float = 0.0,
                yaw: float = 0.0) -> int:
        """How many points lie in their zone with the robot at ``(x, y, yaw)`` of the present ``base_link``."""
        c, s = math.cos(yaw), math.sin(yaw)
        dx, dy = points[:, 0] - x, points[:, 1] - y
        local = np.column_stack([c * dx + s * dy, -s * dx + c * dy])
        return int(self.zones[0].contains(local[~unmapped]).sum() + self.zones[1].contains(local[unmapped]).sum())

    def _time_to_collision(self, points: np.ndarray, unmapped: np.ndarray, v: float, w: float) -> float:
        """First time (s) at which a zone, moving at (v, w) from the origin, holds a point of its kind."""
        n = int(math.ceil(self.time_s / self.step_s))
        poses = arc_poses(0.0, 0.0, 0.0, v, w, self.step_s, n)
        c, s = np.cos(poses[:, 2])[:, None], np.sin(poses[:, 2])[:, None]
        dx, dy = points[None, :, 0] - poses[:, 0:1], points[None, :, 1] - poses[:, 1:2]
        lx, ly = c * dx + s * dy, -s * dx + c * dy                     # (n, P) in each future base_link
        hit = np.zeros(lx.shape, bool)
        for zone, which in ((self.zones[0], ~unmapped), (self.zones[1], unmapped)):
            hit |= which[None, :] & (lx >= zone.x_min_m) & (lx <= zone.x_max_m) & (np.abs(ly) <= zone.half_width_m)
        k = np.flatnonzero(hit.any(axis=1))
        return (int(k[0]) + 1) * self.step_s if len(k) else math.inf

    def filter(self, v: float, w: float, points_base: np.ndarray, unmapped: np.ndarray) -> tuple[float, float]:
        """The command ``(v, w)`` made safe against scan returns ``points_base`` (P, 2) in ``base_link``,
        of which ``unmapped`` (P,) bool the map does not hold."""
        if len(points_base) == 0 or (v == 0.0 and w == 0.0):
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
            after = self.footprint.distance_m(np.column_stack([c * dx + s * dy, -s * dx + c * dy])).min()
            if after < self.footprint.distance_m(pts).min() - 0.005:
                self.actions["stop"] += 1
                return 0.0, 0.0
            self.actions["escape"] += 1
            return v * self.slow_ratio, w * self.slow_ratio
        t_c = self._time_to_collision(pts, unmapped, v, w)
        if t_c < self.time_s:
            scale = t_c / self.time_s
            self.actions["approach"] += 1
            v, w = v * scale, w * scale
        front = pts[:, 0] * math.copysign(1.0, v) > 0.0 if v != 0.0 else np.zeros(len(pts), bool)
        if v != 0.0 and self.slow.contains(pts[front & unmapped]).any() and abs(v) > self.slow_ratio * self.max_v_m_s:
            self.actions["slowdown"] += 1
            v = math.copysign(self.slow_ratio * self.max_v_m_s, v)
        return v, w

    @staticmethod
    def circumscribed(fp: Footprint) -> float:
        return fp.circumscribed_radius_m
