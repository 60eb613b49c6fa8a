"""Planar poses (SE(2)): ``(x_m, y_m, yaw_rad)`` arrays of shape (3,) or (N, 3).

One home for the pose algebra the estimators, the trajectory metrics and the
experiments share: composition, relative motion, angle wrapping and
interpolation in time (yaw unwrapped), and the yaw of a 3D orientation. Yaw is wrapped to
``[-pi, pi)``.
"""

from __future__ import annotations

import math

import numpy as np


def wrap_rad(angle_rad: np.ndarray | float) -> np.ndarray:
    """Angles wrapped to ``[-pi, pi)``, rad (same shape as the input)."""
    return (np.asarray(angle_rad, dtype=float) + math.pi) % (2.0 * math.pi) - math.pi


def yaw_of_quaternion(w: float, x: float, y: float, z: float) -> float:
    """Yaw of the unit quaternion ``(w, x, y, z)``, rad in (-pi, pi]: the heading of its x axis in
    the plane, the z angle of its ZYX (yaw-pitch-roll) Euler angles (REP-103)."""
    return math.atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z))


def yaws_of_quaternions(q: np.ndarray) -> np.ndarray:
    """:func:`yaw_of_quaternion` of quaternions ``q`` (N, 4) ``w, x, y, z`` (MuJoCo's order), rad
    (N,)."""
    w, x, y, z = q[:, 0], q[:, 1], q[:, 2], q[:, 3]
    return np.arctan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z))


def compose(a, b) -> np.ndarray:
    """``a (+) b``: pose(s) ``b`` given in the frame of ``a``, returned in ``a``'s parent frame
    (broadcast)."""
    a, b = np.asarray(a, float), np.asarray(b, float)
    c, s = np.cos(a[..., 2]), np.sin(a[..., 2])
    return np.stack(
        [
            a[..., 0] + c * b[..., 0] - s * b[..., 1],
            a[..., 1] + s * b[..., 0] + c * b[..., 1],
            wrap_rad(a[..., 2] + b[..., 2]),
        ],
        axis=-1,
    )


def between(a, b) -> np.ndarray:
    """``a^-1 (+) b``: pose(s) of ``b`` in the frame of ``a``, i.e. the motion from ``a`` to ``b``
    (broadcast)."""
    a, b = np.asarray(a, float), np.asarray(b, float)
    c, s = np.cos(a[..., 2]), np.sin(a[..., 2])
    dx, dy = b[..., 0] - a[..., 0], b[..., 1] - a[..., 1]
    return np.stack([c * dx + s * dy, -s * dx + c * dy, wrap_rad(b[..., 2] - a[..., 2])], axis=-1)


def inverse(a) -> np.ndarray:
    """``a^-1``: the pose of ``a``'s parent frame in the frame of ``a`` (broadcast)."""
    return between(a, np.zeros(3))


def interpolate(t_s: np.ndarray, pose: np.ndarray, t_query_s) -> np.ndarray:
    """Poses at ``t_query_s`` by linear interpolation of ``(t_s (N,), pose (N, 3))``, yaw unwrapped.

    Stamps outside ``t_s`` get the end values. Returns (M, 3), or (3,) for a scalar query.
    """
    t_s, pose = np.asarray(t_s, float), np.asarray(pose, float)
    q = np.atleast_1d(np.asarray(t_query_s, float))
    yaw = np.interp(q, t_s, np.unwrap(pose[:, 2]))
    out = np.column_stack(
        [np.interp(q, t_s, pose[:, 0]), np.interp(q, t_s, pose[:, 1]), wrap_rad(yaw)]
    )
    return out[0] if np.ndim(t_query_s) == 0 else out


def matrix(x_m: float, y_m: float, yaw_rad: float) -> np.ndarray:
    """Homogeneous 4x4 transform of a planar pose (rotation about z)."""
    c, s = math.cos(yaw_rad), math.sin(yaw_rad)
    t = np.eye(4)
    t[:2, :2] = [[c, -s], [s, c]]
    t[0, 3], t[1, 3] = x_m, y_m
    return t


def from_matrix(t: np.ndarray) -> tuple[float, float, float]:
    """Planar pose ``(x_m, y_m, yaw_rad)`` of a 4x4 transform."""
    return float(t[0, 3]), float(t[1, 3]), math.atan2(t[1, 0], t[0, 0])
