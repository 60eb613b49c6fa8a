"""A sampling MPC in the MPPI style (Williams et al. 2017, "Information theoretic MPC"; nav2's MPPI critics).

Each control cycle, reconstructed from the papers' and nav2's descriptions:

1. ``samples`` control sequences of ``steps`` steps of ``step_s`` are drawn around the nominal
   sequence (the last cycle's optimum shifted by one step), Gaussian noise of ``sigma_v``,
   ``sigma_w``; one sample is the nominal itself and one brakes to rest. Each sequence is made
   feasible from the present velocity: the speed limits and the ramps of :class:`Limits`.
2. The unicycle rolls every sequence out (vectorised: headings and positions as cumulative sums).
3. Critics score each trajectory (lower is better):

   - *obstacles / footprint*: the footprint as two circles covering the rectangle; a circle
     closer to a lethal cell than its radius is a collision (``collision_cost``, larger the
     sooner), and within ``margin_m`` of it a repulsion;
   - *path*: the distance of the trajectory's points to the plan (alignment) and of its end to
     the plan point it could reach (progress);
   - *goal*: near the goal, the distance of the trajectory's points to it;
   - *prefer forward*: backing up costs;
   - *speed near people*: the square of the speed where an obstacle the map does not hold (the
     costmap's obstacle layer: people, pallet jacks) is within ``social_radius_m``.
4. The weights ``exp(-(S - min S) / temperature)`` average the noise into the new nominal,
   smoothed by a 3-step moving average (nav2 smooths with a Savitzky-Golay filter); its first
   step is the command. No feasible sample: stop, and report it (``blocked``).
"""

from __future__ import annotations

import math

import numpy as np

from amr_twin.navigation.costmap import Costmap
from amr_twin.navigation.footprint import Footprint
from amr_twin.navigation.kinematics import Limits
from amr_twin.navigation.path_handler import PathHandler
from amr_twin.navigation.rpp import Twist2D


class Mppi:
    """MPPI local controller (module docstring). ``seed``: the noise stream (same seed, same commands)."""

    def __init__(self, costmap: Costmap, footprint: Footprint, limits: Limits, dt_s: float, *, samples: int = 400,
                 steps: int = 25, step_s: float = 0.1, sigma_v: float = 0.25, sigma_w: float = 0.6,
                 temperature: float = 0.25, margin_m: float = 0.25, social_radius_m: float = 1.0,
                 weights: dict | None = None, seed: int = 0):
        self.costmap, self.limits, self.dt_s = costmap, limits, float(dt_s)
        self.K, self.T, self.step_s = int(samples), int(steps), float(step_s)
        self.sigma = np.array([sigma_v, sigma_w])
        self.temperature, self.margin_m, self.social_radius_m = temperature, margin_m, social_radius_m
        hx = 0.5 * (footprint.x_max_m - footprint.x_min_m)
        cx = 0.5 * (footprint.x_max_m + footprint.x_min_m)
        self.circle_x = np.array([cx - hx / 2, cx + hx / 2])
        self.circle_r = math.hypot(hx / 2, footprint.half_width_m)
        self.w = {"collision": 1e4, "obstacle": 40.0, "align": 3.0, "progress": 4.0, "goal": 6.0,
                  "forward": 3.0, "social": 4.0, **(weights or {})}
        self.rng = np.random.default_rng(seed)
        self.nominal = np.zeros((self.T, 2))

    def reset(self) -> None:
        """Forget the nominal sequence (after a rotation in place or a recovery)."""
        self.nominal[:] = 0.0

    def _feasible(self, u: np.ndarray, v0: float, w0: float) -> np.ndarray:
        lim, dt = self.limits, self.step_s
        u[..., 0] = np.clip(u[..., 0], lim.min_v_m_s, lim.max_v_m_s)
        u[..., 1] = np.clip(u[..., 1], -lim.max_w_rad_s, lim.max_w_rad_s)
        v_prev, w_prev = np.full(len(u), v0), np.full(len(u), w0)
        for t in range(self.T):
            v_prev = u[:, t, 0] = np.clip(u[:, t, 0], v_prev - lim.decel_m_s2 * dt, v_prev + lim.accel_m_s2 * dt)
            w_prev = u[:, t, 1] = np.clip(u[:, t, 1], w_prev - lim.angular_accel_rad_s2 * dt,
                                          w_prev + lim.angular_accel_rad_s2 * dt)
        return u

    def rollout(self, pose, u: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Positions x, y and headings (K, T) of control sequences ``u`` (K, T, 2) from ``pose``."""
        dt = self.step_s
        yaw = pose[2] + np.cumsum(u[..., 1], axis=1) * dt
        mid = yaw - 0.5 * u[..., 1] * dt
        x = pose[0] + np.cumsum(u[..., 0] * np.cos(mid), axis=1) * dt
        y = pose[1] + np.cumsum(u[..., 0] * np.sin(mid), axis=1) * dt
        return x, y, yaw

    def costs(self, x, y, yaw, u, path: PathHandler) -> tuple[np.ndarray, np.ndarray]:
        """Critic cost (K,) of each trajectory and whether it collides (K,)."""
        w, cm, K, T = self.w, self.costmap, x.shape[0], x.shape[1]
        c, s = np.cos(yaw), np.sin(yaw)
        d = np.stack([cm.distance_at(np.column_stack([(x + c * cx).ravel(), (y + s * cx).ravel()])).reshape(K, T)
                      for cx in self.circle_x]).min(0)
        hit = d < self.circle_r
        first = np.where(hit.any(1), hit.argmax(1), T)
        cost = w["collision"] * (hit.any(1)) * (1.0 + (T - first) / T)
        cost += w["obstacle"] * np.maximum(self.circle_r + self.margin_m - d, 0.0).mean(1)
        horizon = self.limits.max_v_m_s * self.T * self.step_s
        ref = path.ahead(horizon + 0.5)[::2, :2]
        sub = np.s_[:, 1::3]
        px, py = x[sub].ravel(), y[sub].ravel()
        dist = np.sqrt(((px[:, None] - ref[None, :, 0]) ** 2 + (py[:, None] - ref[None, :, 1]) ** 2).min(1))
        near_goal = path.remaining_m < 1.0
        if not near_goal:
            cost += w["align"] * dist.reshape(K, -1).mean(1)
            reach = ref[min(len(ref) - 1, int(horizon / (2 * 0.05 + 1e-9)))] if len(ref) else path.goal[:2]
            cost += w["progress"] * np.hypot(x[:, -1] - reach[0], y[:, -1] - reach[1])
        else:
            g = path.goal
            cost += w["goal"] * np.hypot(x - g[0], y - g[1]).mean(1)
        cost += w["forward"] * np.maximum(-u[..., 0], 0.0).mean(1)
        if cm.marked.any():
            dd = cm.obstacle_distance_at(np.column_stack([x.ravel(), y.ravel()])).reshape(K, T)
            near = np.maximum(1.0 - dd / self.social_radius_m, 0.0)
            cost += w["social"] * (u[..., 0] ** 2 * near).mean(1)
        return cost, hit.any(1)

    def command(self, pose, velocity, path: PathHandler) -> Twist2D:
        """The twist for the robot at ``pose`` (x_m, y_m, yaw_rad) moving at ``velocity`` (v, w)."""
        pose = np.asarray(pose, float)
        v0, w0 = (float(v) for v in velocity)
        eps = self.rng.standard_normal((self.K, self.T, 2)) * self.sigma
        eps[0] = 0.0
        u = self.nominal[None] + eps
        u[1, :, :] = 0.0  # the braking sample
        u = self._feasible(u, v0, w0)
        x, y, yaw = self.rollout(pose, u)
        cost, hit = self.costs(x, y, yaw, u, path)
        if hit.all():
            self.reset()
            return Twist2D(*self.limits.ramp(0.0, 0.0, v0, w0, self.dt_s), True)
        wgt = np.exp(-(cost - cost.min()) / self.temperature)
        wgt /= wgt.sum()
        new = (wgt[:, None, None] * u).sum(0)
        new[1:-1] = (new[:-2] + new[1:-1] + new[2:]) / 3.0
        new = self._feasible(new[None], v0, w0)[0]
        v, w = self.limits.ramp(float(new[0, 0]), float(new[0, 1]), v0, w0, self.dt_s)
        t = np.minimum(np.arange(self.T) + self.dt_s / self.step_s, self.T - 1)  # shifted by one control period
        self.nominal = np.column_stack([np.interp(t, np.arange(self.T), new[:, i]) for i in range(2)])
        bx, by, byaw = self.rollout(pose, new[None])
        blocked = bool(self.costs(bx, by, byaw, new[None], path)[1][0])
        return Twist2D(v, w, blocked)
