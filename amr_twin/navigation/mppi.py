"""A sampling MPC in the MPPI style (Williams et al. 2017, "Information theoretic MPC"; nav2's MPPI
critics).

Reasons and measurements: docs/explanation/navigation.md#amr_twinnavigationmppi."""

from __future__ import annotations

import ctypes
import math
from pathlib import Path

import numpy as np

from amr_twin.base.native_build import address, c_array, open_helper
from amr_twin.navigation.costmap import Costmap
from amr_twin.navigation.footprint import Footprint
from amr_twin.navigation.interfaces import LocalController, Twist2D
from amr_twin.navigation.kinematics import Limits
from amr_twin.navigation.path_handler import PathHandler

C_SOURCE = Path(__file__).with_name("mppi_critics.c")
PARAMS = (
    "cx0",
    "cx1",
    "r",
    "margin",
    "collision",
    "obstacle",
    "align",
    "progress",
    "goal",
    "forward",
    "social",
    "people_collision",
    "people",
    "person_radius",
    "clearance",
    "person_margin",
    "social_radius",
    "origin_x",
    "origin_y",
    "res",
    "reach_x",
    "reach_y",
    "goal_x",
    "goal_y",
    "follow",
    "check",
)
"""The C helper's parameter vector (doubles), in the order of its enum."""


def _declare(lib) -> None:
    """The C helper's signatures (addresses as pointers, sizes as ints)."""
    ptr, i32 = ctypes.c_void_p, ctypes.c_int
    lib.mppi_costs.argtypes = [
        i32,
        i32,
        ptr,
        ptr,
        ptr,
        ptr,
        ptr,
        ptr,
        ptr,
        i32,
        i32,
        ptr,
        i32,
        ptr,
        i32,
        ptr,
        ptr,
        i32,
        ptr,
        ptr,
    ]
    lib.mppi_costs.restype = None
    f32 = ctypes.c_float
    lib.mppi_sample.argtypes = [i32, i32, ptr, ptr, ptr, ptr, ptr, ptr, ptr, f32, f32]
    lib.mppi_sample.restype = None
    lib.mppi_headings.argtypes = [i32, i32, ptr, f32, f32, ptr, ptr]
    lib.mppi_headings.restype = None
    lib.mppi_positions.argtypes = [i32, i32, ptr, ptr, ptr, f32, f32, f32, ptr, ptr]
    lib.mppi_positions.restype = None
    if lib.mppi_params_size() != len(PARAMS):
        raise RuntimeError(
            f"{C_SOURCE.name} takes {lib.mppi_params_size()} parameters, mppi.py {len(PARAMS)}"
        )


class Mppi(LocalController):
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
            _declare(self._lib)

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

    def _circles(self, x, y, yaw) -> np.ndarray:
        """Centres (2, T, K, 2) of the footprint's two circles."""
        c, s = np.cos(yaw), np.sin(yaw)
        return np.stack(
            [
                np.stack([x + c * x.dtype.type(cx), y + s * x.dtype.type(cx)], axis=-1)
                for cx in self.circle_x
            ]
        )

    def _people_costs(self, circles, u, people, t_s: float) -> np.ndarray:
        """The people critics (module docstring) for the tracked ``people`` at ``t_s``; (K,)."""
        w, T = self.w, u.shape[0]
        at = people.at(t_s + self.step_s * np.arange(1, T + 1), self.prediction_s)  # (N, T, 2)
        d = np.sqrt(((circles[:, None] - at[None, :, :, None, :]) ** 2).sum(-1))  # (2, N, T, K)
        gap = d.min(axis=(0, 1)) - self.circle_r - self.person_radius_m  # (T, K)
        now = min(
            self.person_clearance_m, float(gap[0].max()) - 0.02
        )  # already closer: do not come closer
        close = gap < now
        first = np.where(close.any(0), close.argmax(0), T)
        cost = w["people_collision"] * close.any(0) * (1.0 + (T - first) / T)
        cost += w["people"] * np.maximum(self.person_margin_m - gap, 0.0).mean(0)
        near = np.maximum(1.0 - gap / self.social_radius_m, 0.0)
        return cost + w["social"] * (u[..., 0] ** 2 * near).mean(0)

    def costs(
        self, x, y, yaw, u, path: PathHandler, people=None, t_s: float = 0.0
    ) -> tuple[np.ndarray, np.ndarray]:
        """Critic cost (K,) of each trajectory (T, K) and whether it collides (K,) with what the
        costmap holds."""
        w, T = self.w, x.shape[0]
        horizon = self.limits.max_v_m_s * self.T * self.step_s
        ref = path.ahead(horizon + 0.5)[::2, :2]
        follow = path.remaining_m >= 1.0
        reach = (
            ref[min(len(ref) - 1, int(horizon / (2 * 0.05 + 1e-9)))] if len(ref) else path.goal[:2]
        )
        if self._lib is not None:
            return self._costs_c(x, y, yaw, u, ref, reach, follow, path.goal, people, t_s)
        clear, hit = self._footprint(x, y, np.cos(yaw), np.sin(yaw))
        any_hit = hit.any(0)
        first = np.where(any_hit, hit.argmax(0), T)
        cost = w["collision"] * any_hit * (1.0 + (T - first) / T)
        cost += w["obstacle"] * np.maximum(np.float32(self.margin_m) - clear, 0.0).mean(0)
        if follow:
            px, py = x[1::3], y[1::3]  # (T/3, K)
            dist = np.sqrt(
                ((px[..., None] - ref[:, 0]) ** 2 + (py[..., None] - ref[:, 1]) ** 2).min(-1)
            )
            cost += w["align"] * dist.mean(0)
            cost += w["progress"] * np.hypot(x[-1] - reach[0], y[-1] - reach[1])
        else:
            g = path.goal
            cost += w["goal"] * np.hypot(x - g[0], y - g[1]).mean(0)
        cost += w["forward"] * np.maximum(-u[..., 0], 0.0).mean(0)
        if people is not None and len(people):
            cost += self._people_costs(self._circles(x, y, yaw), u, people, t_s)
        return cost, any_hit

    def _footprint(self, x, y, c, s) -> tuple[np.ndarray, np.ndarray]:
        """The footprint critic's clearance (T, K) (float32, m; ``margin_m`` where the centre is
        beyond
        :attr:`check_m`) and collisions (T, K) of poses at ``x, y`` heading ``c, s`` (cos, sin)."""
        cm = self.costmap
        d = cm.distance_at(np.column_stack([x.ravel(), y.ravel()])).reshape(x.shape)
        clear = np.full(x.shape, np.float32(self.margin_m), np.float32)
        near = d < np.float32(self.check_m)
        xs, ys, cs, ss = (a[near][:, None] for a in (x, y, c, s))
        px = xs + cs * self._ox - ss * self._oy
        py = ys + ss * self._ox + cs * self._oy
        clear[near] = (
            cm.distance_at(np.column_stack([px.ravel(), py.ravel()])).reshape(px.shape).min(1)
        )
        return clear, (clear <= 0.0) | (d <= 0.0)

    def _costs_c(
        self, x, y, yaw, u, ref, reach, follow, goal, people, t_s
    ) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`costs` by the C helper (the same critics; the headings enter as their cos and
        sin)."""
        cm, (T, K) = self.costmap, x.shape
        p = self._params
        p[17:25] = (
            cm.origin_xy_m[0],
            cm.origin_xy_m[1],
            cm.resolution_m,
            reach[0],
            reach[1],
            goal[0],
            goal[1],
            float(follow),
        )
        ref = c_array(ref, np.float64)
        if people is not None and len(people):
            at = c_array(
                people.at(t_s + self.step_s * np.arange(1, T + 1), self.prediction_s), np.float64
            )
        else:
            at = np.zeros((0, T, 2))
        dist = c_array(cm.dist_m, np.float32)
        cost, hit = np.empty(K), np.empty(K, np.uint8)
        x, y, u = c_array(x, np.float32), c_array(y, np.float32), c_array(u, np.float32)
        c, s = (
            np.cos(yaw, dtype=np.float32),
            np.sin(yaw, dtype=np.float32),
        )  # kept alive over the call
        self._lib.mppi_costs(
            T,
            K,
            address(x),
            address(y),
            address(c),
            address(s),
            address(u),
            address(p),
            address(dist),
            dist.shape[0],
            dist.shape[1],
            address(ref),
            len(ref),
            address(at) if len(at) else None,
            len(at),
            address(cost),
            address(hit),
            len(self._ox),
            address(self._ox),
            address(self._oy),
        )
        return cost, hit.view(bool)

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
