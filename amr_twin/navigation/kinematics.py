"""Velocity limits and the motions every controller shares: ramps, rotation in place, arcs.

The limits are the navigation's (``navigation:`` in ``models/amr/amr.yaml``), chosen inside
what the drive can do: the improved firmware slews each wheel's reference at 150 RPM/s
(1.96 m/s^2 at the rim), and its PI settles a step in a few hundred ms. A command that asks for
more is followed late, which a controller would read as a disturbance.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Limits:
    """Speed and acceleration limits of a twist ``(v, w)``; m/s, rad/s, m/s^2, rad/s^2."""

    max_v_m_s: float = 0.8
    min_v_m_s: float = -0.25
    max_w_rad_s: float = 1.0
    accel_m_s2: float = 0.8
    decel_m_s2: float = 1.0
    angular_accel_rad_s2: float = 2.0

    def ramp(
        self, v: float, w: float, v_prev: float, w_prev: float, dt_s: float
    ) -> tuple[float, float]:
        """``(v, w)`` clipped to the limits and to the accelerations from ``(v_prev, w_prev)`` over
        ``dt_s``."""
        v = min(max(v, self.min_v_m_s), self.max_v_m_s)
        w = min(max(w, -self.max_w_rad_s), self.max_w_rad_s)
        slowing = abs(v) < abs(v_prev) and v * v_prev >= 0.0
        dv = (self.decel_m_s2 if slowing else self.accel_m_s2) * dt_s
        v = min(max(v, v_prev - dv), v_prev + dv)
        dw = self.angular_accel_rad_s2 * dt_s
        w = min(max(w, w_prev - dw), w_prev + dw)
        return v, w


def wrap(angle_rad):
    """Angles wrapped to [-pi, pi)."""
    return (np.asarray(angle_rad) + math.pi) % (2.0 * math.pi) - math.pi


def rotation_rate(
    error_rad: float,
    limits: Limits,
    w_prev: float,
    dt_s: float,
    gain_per_s: float = 1.5,
    min_rate_rad_s: float = 0.15,
) -> float:
    """Yaw rate that turns in place through ``error_rad`` and stops there: proportional, at least
    ``min_rate_rad_s`` (the drive cannot hold a crawl), at most what decelerates to rest at the
    target."""
    stop_rate = math.sqrt(2.0 * limits.angular_accel_rad_s2 * 0.8 * abs(error_rad))
    rate = min(max(gain_per_s * abs(error_rad), min_rate_rad_s), stop_rate, limits.max_w_rad_s)
    w = math.copysign(rate, error_rad)
    dw = limits.angular_accel_rad_s2 * dt_s
    return min(max(w, w_prev - dw), w_prev + dw)


def arc_poses(
    x_m: float, y_m: float, yaw_rad: float, v: float, w: float, dt_s: float, n: int
) -> np.ndarray:
    """Poses (n, 3) after 1..n steps of ``dt_s`` at the constant twist ``(v, w)`` (exact
    unicycle)."""
    t = dt_s * np.arange(1, n + 1)
    yaw = yaw_rad + w * t
    if abs(w) < 1e-9:
        x, y = x_m + v * t * math.cos(yaw_rad), y_m + v * t * math.sin(yaw_rad)
    else:
        x = x_m + v / w * (np.sin(yaw) - math.sin(yaw_rad))
        y = y_m - v / w * (np.cos(yaw) - math.cos(yaw_rad))
    return np.column_stack([np.broadcast_to(x, t.shape), np.broadcast_to(y, t.shape), yaw])


def to_map(poses: np.ndarray, points_base: np.ndarray) -> np.ndarray:
    """Points (P, 2) of ``base_link`` placed at each of ``poses`` (n, 3): (n, P, 2) in ``map``."""
    c, s = np.cos(poses[:, 2])[:, None], np.sin(poses[:, 2])[:, None]
    px, py = points_base[None, :, 0], points_base[None, :, 1]
    return np.stack([poses[:, 0:1] + c * px - s * py, poses[:, 1:2] + s * px + c * py], axis=-1)
