"""A sampling MPC in the MPPI style (Williams et al. 2017, "Information theoretic MPC"; nav2's MPPI
critics).

Reasons and measurements: docs/explanation/navigation.md#amr_twinnavigationmppi."""

from __future__ import annotations

import math

import numpy as np

from amr_twin.base.native_build import address, c_array, open_helper
from amr_twin.navigation.costmap import Costmap
from amr_twin.navigation.footprint import Footprint
from amr_twin.navigation.interfaces import LocalController, Twist2D
from amr_twin.navigation.kinematics import Limits
from amr_twin.navigation.mppi_critics import C_SOURCE, MppiCritics, declare
from amr_twin.navigation.path_handler import PathHandler


class Mppi(MppiCritics, LocalController):
    """MPPI local controller (module docstring). ``seed``: the noise stream (same seed, same
    commands). ``native=False``: the NumPy critics rather than their C twin (:attr:`engine` says
    which run).

    Arrays are time-major inside: controls (T, K, 2), trajectories (T, K), so that each step of the
    ramps' clipping works on contiguous memory.
    """

    sees_people = True

    def __init__(
        self,
        costmap: Costmap,
        footprint: Footprint,
        limits: Limits,
        dt_s: float,
        *,
        samples: int = 400,
        steps: int = 25,
        step_s: float = 0.1,
        sigma_v: float = 0.25,
        sigma_w: float = 0.6,
        temperature: float = 0.25,
        margin_m: float = 0.25,
        social_radius_m: float = 1.0,
        person_radius_m: float = 0.25,
        person_clearance_m: float = 0.25,
        person_margin_m: float = 0.6,
        prediction_s: float = 2.5,
        narrow_m: float = 0.0,
        narrow_v_m_s: float = 0.3,
        weights: dict | None = None,
        seed: int = 0,
        native: bool = True,
    ):
        self.costmap, self.limits, self.dt_s = costmap, limits, float(dt_s)
        self.K, self.T, self.step_s = int(samples), int(steps), float(step_s)
        self.sigma = np.array([sigma_v, sigma_w], np.float32)
        self.temperature, self.margin_m, self.social_radius_m = (
            temperature,
            margin_m,
            social_radius_m,
        )
        self.person_radius_m, self.person_clearance_m = person_radius_m, person_clearance_m
        self.person_margin_m, self.prediction_s = person_margin_m, prediction_s
        hx = 0.5 * (footprint.x_max_m - footprint.x_min_m)
        cx = 0.5 * (footprint.x_max_m + footprint.x_min_m)
        self.circle_x = np.array([cx - hx / 2, cx + hx / 2])
        self.circle_r = math.hypot(hx / 2, footprint.half_width_m)
        outline = footprint.outline_xy_m(costmap.resolution_m).astype(np.float32)
        self._ox, self._oy = outline[:, 0].copy(), outline[:, 1].copy()
        self.check_m = footprint.circumscribed_radius_m + margin_m + costmap.resolution_m
        """Centres farther than this from an obstacle: the footprint's clearance is beyond
        ``margin_m``, m."""
        self.narrow_m, self.narrow_v_m_s = float(narrow_m), float(narrow_v_m_s)
        self.w = {
            "collision": 1e4,
            "obstacle": 40.0,
            "align": 3.0,
            "progress": 4.0,
            "goal": 6.0,
            "forward": 3.0,
            "social": 4.0,
            "people_collision": 2e3,
            "people": 8.0,
            **(weights or {}),
        }
        self.rng = np.random.default_rng(seed)
        self.nominal = np.zeros((self.T, 2))
        f32 = (
            np.float32
        )  # the samples in single precision: half the memory traffic, the same decisions
        self._u_min = np.array([limits.min_v_m_s, -limits.max_w_rad_s], f32)
        self._u_max = np.array([limits.max_v_m_s, limits.max_w_rad_s], f32)
        self._down = np.array([limits.decel_m_s2, limits.angular_accel_rad_s2], f32) * f32(
            self.step_s
        )
        self._up = np.array([limits.accel_m_s2, limits.angular_accel_rad_s2], f32) * f32(
            self.step_s
        )
        self._lib, self.engine = open_helper(C_SOURCE, native)
        if self._lib is not None:
            w = self.w
            self._params = np.array(
                [
                    *self.circle_x,
                    self.circle_r,
                    margin_m,
                    w["collision"],
                    w["obstacle"],
                    w["align"],
                    w["progress"],
                    w["goal"],
                    w["forward"],
                    w["social"],
                    w["people_collision"],
                    w["people"],
                    person_radius_m,
                    person_clearance_m,
                    person_margin_m,
                    social_radius_m,
                    0.0,
                    0.0,
                    1.0,
                    0.0,
                    0.0,
                    0.0,
                    0.0,
                    0.0,
                    self.check_m,
                ]
            )
            self._bounds = [address(a) for a in (self._u_min, self._u_max, self._down, self._up)]
            declare(self._lib)

    def reset(self) -> None:
        """Forget the nominal sequence (after a rotation in place or a recovery)."""
        self.nominal[:] = 0.0

    def _feasible(self, u: np.ndarray, v0: float, w0: float) -> np.ndarray:
        """``u`` (T, K, 2) clipped in place to the speed limits and, step by step from ``(v0, w0)``,
        to the ramps."""
        np.clip(u, self._u_min, self._u_max, out=u)
        prev = np.array([v0, w0], u.dtype)
        for t in range(self.T):
            step = u[t]
            np.maximum(step, prev - self._down, out=step)
            np.minimum(step, prev + self._up, out=step)
            prev = step
        return u

    def _sample(self, v0: float, w0: float) -> np.ndarray:
        """Step 1 of the module docstring: the feasible control sequences (T, K, 2) of this
        cycle."""
        u = self.rng.standard_normal((self.T, self.K, 2), dtype=np.float32)
        if self._lib is not None:
            self._lib.mppi_sample(
                self.T,
                self.K,
                address(u),
                address(self.sigma),
                address(self.nominal),
                *self._bounds,
                v0,
                w0,
            )
            return u
        u *= self.sigma
        u += self.nominal[:, None, :]
        u[:, 0] = self.nominal
        u[:, 1] = 0.0  # the braking sample
        return self._feasible(u, v0, w0)

    def rollout(self, pose, u: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Positions x, y and headings (T, K) of control sequences ``u`` (T, K, 2) from ``pose``."""
        if self._lib is not None:  # the C helper's sums around NumPy's cos and sin: the same bits
            u, (T, K) = c_array(u, np.float32), u.shape[:2]
            yaw, mid, x, y = (np.empty((T, K), np.float32) for _ in range(4))
            self._lib.mppi_headings(
                T, K, address(u), self.step_s, pose[2], address(yaw), address(mid)
            )
            cm, sm = np.cos(mid), np.sin(mid)
            self._lib.mppi_positions(
                T,
                K,
                address(u),
                address(cm),
                address(sm),
                self.step_s,
                pose[0],
                pose[1],
                address(x),
                address(y),
            )
            return x, y, yaw
        dt = u.dtype.type(self.step_s)
        yaw = np.cumsum(u[..., 1], axis=0)
        yaw *= dt
        yaw += u.dtype.type(pose[2])
        mid = yaw - 0.5 * dt * u[..., 1]
        x = np.cumsum(u[..., 0] * np.cos(mid), axis=0)
        x *= dt
        x += u.dtype.type(pose[0])  # map coordinates of tens of m: float32 keeps them to about 4 um
        y = np.cumsum(u[..., 0] * np.sin(mid), axis=0)
        y *= dt
        y += u.dtype.type(pose[1])
        return x, y, yaw

    def command(self, pose, velocity, path: PathHandler, people=None, t_s: float = 0.0) -> Twist2D:
        """The twist for the robot at ``pose`` (x_m, y_m, yaw_rad) moving at ``velocity`` (v, w), at
        time ``t_s`` with the tracked ``people`` (:class:`~amr_twin.navigation.people.People`)
        about."""
        pose = np.asarray(pose, float)
        v0, w0 = (float(v) for v in velocity)
        ahead = path.ahead(1.0)[:, :2]
        narrow = (
            self.narrow_m > 0.0 and float(self.costmap.distance_at(ahead).min()) < self.narrow_m
        )
        self._u_max[0] = (
            min(self.limits.max_v_m_s, self.narrow_v_m_s) if narrow else self.limits.max_v_m_s
        )
        u = self._sample(v0, w0)
        x, y, yaw = self.rollout(pose, u)
        cost, hit = self.costs(x, y, yaw, u, path, people, t_s)
        if hit.all():
            self.reset()
            return Twist2D(*self.limits.ramp(0.0, 0.0, v0, w0, self.dt_s), True)
        wgt = np.exp(-(cost - cost.min()) / self.temperature)
        wgt /= wgt.sum()
        # a weighted mean of feasible sequences, and its 3-step moving average, are feasible (the
        # limits and ramps are convex constraints): no second clipping
        new = np.tensordot(u, wgt.astype(u.dtype), axes=([1], [0])).astype(float)  # (T, 2)
        new[1:-1] = (new[:-2] + new[1:-1] + new[2:]) / 3.0
        v, w = self.limits.ramp(float(new[0, 0]), float(new[0, 1]), v0, w0, self.dt_s)
        shift = min(
            self.dt_s / self.step_s, 1.0
        )  # shifted by one control period, the last step held
        self.nominal[:-1] = (1.0 - shift) * new[:-1] + shift * new[1:]
        self.nominal[-1] = new[-1]
        return Twist2D(
            v, w, bool(wgt[hit].sum() > 0.5)
        )  # most of the weight on colliding samples: blocked
