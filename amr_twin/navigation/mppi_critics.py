"""The MPPI controller's critics: the cost of each sampled trajectory, in NumPy or by their C twin
(``mppi_critics.c``), and the C helper's parameters and signatures.

Reasons and measurements: docs/explanation/navigation.md#amr_twinnavigationmppi."""

from __future__ import annotations

import ctypes
from pathlib import Path

import numpy as np

from amr_twin.base.native_build import address, c_array
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


def declare(lib) -> None:
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
            f"{C_SOURCE.name} takes {lib.mppi_params_size()} parameters, "
            f"mppi_critics.py {len(PARAMS)}"
        )


class MppiCritics:
    """The critics of :class:`amr_twin.navigation.mppi.Mppi`, which holds their weights ``w``, the
    costmap, the footprint's circles and outline, the people settings and the C helper ``_lib``."""

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
