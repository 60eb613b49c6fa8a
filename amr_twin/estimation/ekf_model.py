"""Motion and measurement models of the planar EKF (pure functions, no filter, bus or clock).

State (6,)
    ``[x_m, y_m, yaw_rad, v_m_s, w_rad_s, gyro_bias_rad_s]`` (indices :data:`X`,
    :data:`Y`, :data:`YAW`, :data:`V`, :data:`W`, :data:`BG`): the planar pose in
    the world frame (``odom``, or ``map`` when UWB is fused), the forward speed and
    yaw rate of ``base_link``, and the gyro's z bias.
Prediction
    Constant velocity on a unicycle (:func:`predict_mean`, Jacobian
    :func:`transition_jacobian`): ``x += v dt cos(yaw + w dt / 2)``,
    ``y += v dt sin(yaw + w dt / 2)``, ``yaw += w dt``; process noise
    (:func:`process_noise`) from white linear and angular accelerations
    (``accel_sigma_m_s2``, ``alpha_sigma_rad_s2``) and a bias random walk.
Measurements
    ``odom`` twist: ``v`` and ``w`` (:func:`linear_model` of ``[V, W]``), from the
    message's twist or from two poses (:func:`pose_difference_twist`);
    ``imu/data_raw``: ``gyro_z = w + b`` (:func:`gyro_model`); ``uwb/range``:
    ``r = sqrt(|p_tag - p_anchor|^2 + dz^2)`` with the tag ``p_tag = p + R(yaw) t``,
    Jacobian in x, y, yaw (:func:`range_model`).

The node that runs the filter on these is :class:`amr_twin.estimation.ekf.EkfNode`.
"""

from __future__ import annotations

import math
from typing import Callable, Sequence

import numpy as np

from amr_twin.model.config_estimation import EkfCfg

X, Y, YAW, V, W, BG = range(6)
N_STATE = 6


def predict_mean(x: np.ndarray, dt_s: float) -> None:
    """Advance the state ``x`` (6, 1) by ``dt_s`` s at constant velocity, in place."""
    heading = x[YAW, 0] + 0.5 * x[W, 0] * dt_s
    x[X, 0] += x[V, 0] * dt_s * math.cos(heading)
    x[Y, 0] += x[V, 0] * dt_s * math.sin(heading)
    x[YAW, 0] += x[W, 0] * dt_s


def transition_jacobian(x: np.ndarray, dt_s: float) -> np.ndarray:
    """Jacobian ``F`` (6, 6) of :func:`predict_mean` at the state ``x`` (6,) over ``dt_s`` s."""
    yaw, v, w = float(x[YAW]), float(x[V]), float(x[W])
    c = math.cos(yaw + 0.5 * w * dt_s)
    s = math.sin(yaw + 0.5 * w * dt_s)
    vdt = v * dt_s
    return np.array(
        [
            [1.0, 0.0, -vdt * s, dt_s * c, -vdt * s * 0.5 * dt_s, 0.0],
            [0.0, 1.0, vdt * c, dt_s * s, vdt * c * 0.5 * dt_s, 0.0],
            [0.0, 0.0, 1.0, 0.0, dt_s, 0.0],
            [0.0, 0.0, 0.0, 1.0, 0.0, 0.0],
            [0.0, 0.0, 0.0, 0.0, 1.0, 0.0],
            [0.0, 0.0, 0.0, 0.0, 0.0, 1.0],
        ]
    )


def process_noise(x: np.ndarray, dt_s: float, cfg: EkfCfg) -> np.ndarray:
    """Process noise ``Q`` (6, 6) over ``dt_s`` s at the state ``x`` (6,), SI units squared.

    White linear acceleration along the heading (``cfg.accel_sigma_m_s2``), white
    angular acceleration (``cfg.alpha_sigma_rad_s2``) and a random walk of the gyro
    bias (``cfg.gyro_bias_walk_rad_s_sqrt_s``); 1e-12 m^2/s on x and y keeps ``P``
    positive definite across the heading.
    """
    yaw, w = float(x[YAW]), float(x[W])
    c = math.cos(yaw + 0.5 * w * dt_s)
    s = math.sin(yaw + 0.5 * w * dt_s)
    qa, qw = cfg.accel_sigma_m_s2**2, cfg.alpha_sigma_rad_s2**2
    d2, d3 = dt_s * dt_s / 2.0, dt_s**3 / 3.0
    qxy, qxv, qyv, qyw = qa * d3 * c * s, qa * d2 * c, qa * d2 * s, qw * d2
    return np.array(
        [
            [qa * d3 * c * c + 1e-12 * dt_s, qxy, 0.0, qxv, 0.0, 0.0],
            [qxy, qa * d3 * s * s + 1e-12 * dt_s, 0.0, qyv, 0.0, 0.0],
            [0.0, 0.0, qw * d3, 0.0, qyw, 0.0],
            [qxv, qyv, 0.0, qa * dt_s, 0.0, 0.0],
            [0.0, 0.0, qyw, 0.0, qw * dt_s, 0.0],
            [0.0, 0.0, 0.0, 0.0, 0.0, cfg.gyro_bias_walk_rad_s_sqrt_s**2 * dt_s],
        ]
    )


def linear_model(rows: Sequence[int], n: int = N_STATE) -> tuple[Callable, Callable, np.ndarray]:
    """``(HJacobian, Hx, H)`` of a measurement that picks the state entries ``rows``.

    ``H`` has shape (len(rows), n); the two callables take the state (n, 1) as
    filterpy's ``ExtendedKalmanFilter.update`` calls them.
    """
    H = np.zeros((len(rows), n))
    for i, r in enumerate(rows):
        H[i, r] = 1.0
    return (lambda x: H), (lambda x: H @ x), H


def gyro_model() -> tuple[Callable, Callable]:
    """``(HJacobian, Hx)`` of the gyro's z rate, ``w + gyro_bias`` (H shape (1, 6))."""
    H_gyro = np.zeros((1, N_STATE))
    H_gyro[0, W] = H_gyro[0, BG] = 1.0
    return (lambda x: H_gyro), (lambda x: H_gyro @ x)


def range_model(
    x: np.ndarray, anchor_xy_m: np.ndarray, tag_xy_m: np.ndarray, dz_m: float
) -> tuple[float, np.ndarray]:
    """Predicted UWB range and its Jacobian.

    Parameters
    ----------
    x : ndarray, shape (6,)
        State.
    anchor_xy_m : ndarray, shape (2,)
        Anchor position in the world frame, m.
    tag_xy_m : ndarray, shape (2,)
        Tag position in ``base_link``, m.
    dz_m : float
        Anchor height above the tag, m.

    Returns
    -------
    r : float
        Range, m.
    H : ndarray, shape (1, 6)
        Jacobian of ``r`` (zero within 1e-9 m of the anchor).
    """
    yaw = x[YAW]
    c, s = math.cos(yaw), math.sin(yaw)
    tx, ty = tag_xy_m
    ax, ay = anchor_xy_m
    ex, ey = x[X] + c * tx - s * ty - ax, x[Y] + s * tx + c * ty - ay
    r = math.sqrt(ex * ex + ey * ey + dz_m * dz_m)
    H = np.zeros((1, N_STATE))
    if r > 1e-9:
        H[0, X], H[0, Y] = ex / r, ey / r
        H[0, YAW] = (ex * (-s * tx - c * ty) + ey * (c * tx - s * ty)) / r
    return r, H


def pose_difference_twist(
    prev: tuple[float, float, float, float], now: tuple[float, float, float, float]
) -> tuple[float, float]:
    """``(v_m_s, w_rad_s)`` between two poses ``(t_s, x_m, y_m, yaw_rad)``, ``now[0] > prev[0]``.

    The forward speed is the displacement projected on the mid-heading; the yaw
    difference is wrapped to (-pi, pi].
    """
    dt = now[0] - prev[0]
    dyaw = math.atan2(math.sin(now[3] - prev[3]), math.cos(now[3] - prev[3]))
    mid = prev[3] + 0.5 * dyaw
    v = ((now[1] - prev[1]) * math.cos(mid) + (now[2] - prev[2]) * math.sin(mid)) / dt
    return v, dyaw / dt


def odometry_covariances(P: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The state covariance ``P`` (6, 6) as ``nav_msgs/Odometry`` pose and twist covariances.

    Returns
    -------
    pose_cov, twist_cov : ndarray, shape (36,)
        Row-major 6x6 over (x, y, z, rot x, rot y, rot z) and (vx, vy, vz, wx, wy, wz);
        the entries the planar state does not hold are 0.
    """
    pose_cov = np.zeros((6, 6))
    pose_cov[_POSE_ROWS] = P[_POSE_STATE]
    twist_cov = np.zeros((6, 6))
    twist_cov[_TWIST_ROWS] = P[_TWIST_STATE]
    return pose_cov.ravel(), twist_cov.ravel()


_POSE_ROWS, _POSE_STATE = np.ix_((0, 1, 5), (0, 1, 5)), np.ix_((X, Y, YAW), (X, Y, YAW))
"""Rows/columns (x, y, rot z) of a pose covariance and the state entries they hold."""
_TWIST_ROWS, _TWIST_STATE = np.ix_((0, 5), (0, 5)), np.ix_((V, W), (V, W))
"""Rows/columns (vx, wz) of a twist covariance and the state entries they hold."""
