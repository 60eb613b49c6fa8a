"""Trajectory errors of a planar pose estimate against the truth: ATE and RPE.

Both trajectories are ``(N, 3)`` arrays of ``[x_m, y_m, yaw_rad]`` in one frame
(``map``) with their stamps in seconds. The truth is interpolated at the
estimate's stamps (x, y linearly; yaw linearly on the unwrapped angle, then
wrapped to ``(-pi, pi]``); estimate samples outside the truth's time span are
left out.

Reasons and measurements: docs/explanation/fusion.md#amr_twinanalysistrajectory."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from amr_twin.analysis import se2

RPE_REL_TOL = 0.1
"""A pair is kept when its travelled distance is within this fraction of ``rpe_delta_m`` (evo's
``rel_delta_tol``)."""


@dataclass(frozen=True)
class TrajectoryErrors:
    """Errors of an estimate against the truth (see the module docstring).

    Attributes
    ----------
    ate_m : float
        Absolute trajectory error, RMSE of the position error, m.
    rpe_trans_m : float
        Relative pose error per ``rpe_delta_m`` travelled, translation RMSE, m (NaN if no pair).
    rpe_rot_deg : float
        Relative pose error per ``rpe_delta_m`` travelled, rotation RMSE, deg (NaN if no pair).
    final_pos_err_m : float
        Position error at the last estimate sample, m.
    final_yaw_err_deg : float
        Absolute heading error at the last estimate sample, deg.
    rms_yaw_err_deg : float
        RMS of the heading error over the samples, deg.
    max_yaw_err_deg : float
        Largest absolute heading error, deg.
    length_m : float
        Length of the true path over the estimate's samples, m.
    """

    ate_m: float
    rpe_trans_m: float
    rpe_rot_deg: float
    final_pos_err_m: float
    final_yaw_err_deg: float
    rms_yaw_err_deg: float
    max_yaw_err_deg: float
    length_m: float


def _checked(name_t: str, t_s, name_pose: str, pose) -> tuple[np.ndarray, np.ndarray]:
    t = np.asarray(t_s, dtype=float)
    p = np.asarray(pose, dtype=float)
    if t.ndim != 1 or t.size < 2:
        raise ValueError(f"{name_t}: shape {t.shape} must be (N,) with N >= 2")
    if p.shape != (t.size, 3):
        raise ValueError(
            f"{name_pose}: shape {p.shape} must be (N, 3) = ({t.size}, 3), rows [x_m, y_m, yaw_rad]"
        )
    if not np.isfinite(t).all():
        raise ValueError(f"{name_t}: all stamps must be finite")
    if not np.isfinite(p).all():
        raise ValueError(f"{name_pose}: all values must be finite")
    if np.any(np.diff(t) < 0):
        raise ValueError(f"{name_t}: stamps must be non-decreasing")
    return t, p


def align_se2(xy_est_m: np.ndarray, xy_true_m: np.ndarray) -> tuple[float, np.ndarray]:
    """Rotation ``theta_rad`` and translation ``t_m (2,)`` minimising ``sum |R p_est + t -
    p_true|^2``.

    Umeyama (1991) / Horn closed form in 2D, without scale. Inputs are (N, 2), m.
    """
    mu_e, mu_t = xy_est_m.mean(axis=0), xy_true_m.mean(axis=0)
    e, q = xy_est_m - mu_e, xy_true_m - mu_t
    theta = math.atan2(float(np.sum(e[:, 0] * q[:, 1] - e[:, 1] * q[:, 0])), float(np.sum(e * q)))
    c, s = math.cos(theta), math.sin(theta)
    rot = np.array([[c, -s], [s, c]])
    return theta, mu_t - rot @ mu_e


def _relative(pose: np.ndarray, i: np.ndarray, j: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Relative motions ``pose_i^-1 pose_j``: translation (K, 2) in frame i and rotation (K,)."""
    d = pose[j, :2] - pose[i, :2]
    c, s = np.cos(pose[i, 2]), np.sin(pose[i, 2])
    return np.column_stack([c * d[:, 0] + s * d[:, 1], -s * d[:, 0] + c * d[:, 1]]), pose[
        j, 2
    ] - pose[i, 2]


def rpe_pairs(
    pose_true: np.ndarray, rpe_delta_m: float, rel_tol: float = RPE_REL_TOL
) -> tuple[np.ndarray, np.ndarray]:
    """Index pairs ``(i, j)`` of the RPE: for each ``i`` the later ``j`` travelled nearest
    ``rpe_delta_m``.

    As ``evo.core.filters.filter_pairs_by_path(..., all_pairs=True)`` with ``tol =
    rel_tol * rpe_delta_m``, vectorised: the distance travelled is non-decreasing,
    so the nearest is one of the two samples around ``d_i + delta`` (the first of
    a run of equal distances).
    """
    d = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(pose_true[:, :2], axis=0).T))])
    n = len(d)
    i = np.arange(n - 1)
    target = d[i] + rpe_delta_m
    hi = np.searchsorted(d, target, side="left")  # first with d >= target (n: none)
    lo = np.maximum(
        np.searchsorted(d, d[np.maximum(hi - 1, 0)], side="left"), i + 1
    )  # first of the run below
    hi_ok = hi < n
    err_hi = np.where(hi_ok, np.abs(d[np.minimum(hi, n - 1)] - d[i] - rpe_delta_m), np.inf)
    lo_ok = hi - 1 >= i + 1
    err_lo = np.where(lo_ok, np.abs(d[np.minimum(lo, n - 1)] - d[i] - rpe_delta_m), np.inf)
    use_lo = err_lo <= err_hi
    j = np.where(use_lo, lo, hi)
    err = np.where(use_lo, err_lo, err_hi)
    keep = err <= rel_tol * rpe_delta_m
    return i[keep], j[keep]


def rpe(pose_est: np.ndarray, pose_true: np.ndarray, rpe_delta_m: float) -> tuple[float, float]:
    """RPE ``(trans_m, rot_deg)`` RMSEs of time-matched ``(N, 3)`` poses (module docstring); NaN if
    no pair."""
    i, j = rpe_pairs(pose_true, rpe_delta_m)
    if i.size == 0:
        return math.nan, math.nan
    t_true, r_true = _relative(pose_true, i, j)
    t_est, r_est = _relative(pose_est, i, j)
    # E = rel_true^-1 rel_est has translation R_true^T (t_est - t_true): its norm is |t_est -
    # t_true|
    err_t = np.hypot(*(t_est - t_true).T)
    err_r = np.abs(se2.wrap_rad(r_est - r_true))
    return float(np.sqrt(np.mean(err_t**2))), float(np.degrees(np.sqrt(np.mean(err_r**2))))


def errors(
    t_est_s, pose_est, t_true_s, pose_true, rpe_delta_m: float = 1.0, align: bool = False
) -> TrajectoryErrors:
    """Errors of an estimate against the truth.

    Parameters
    ----------
    t_est_s : array_like, shape (N,)
        Estimate stamps, s, non-decreasing.
    pose_est : array_like, shape (N, 3)
        Estimated ``[x_m, y_m, yaw_rad]``.
    t_true_s : array_like, shape (M,)
        Truth stamps, s, non-decreasing.
    pose_true : array_like, shape (M, 3)
        True ``[x_m, y_m, yaw_rad]`` in the estimate's frame.
    rpe_delta_m : float
        Distance travelled per RPE pair, m (> 0).
    align : bool
        Align the estimate onto the truth by the least-squares SE(2) transform first
        (changes ATE and the heading errors, not RPE).

    Returns
    -------
    TrajectoryErrors

    Raises
    ------
    ValueError
        Bad shapes, non-finite values, decreasing stamps, ``rpe_delta_m <= 0``, or
        fewer than 2 estimate samples inside the truth's time span; the message names the argument.
    """
    t_est, p_est = _checked("t_est_s", t_est_s, "pose_est", pose_est)
    t_true, p_true = _checked("t_true_s", t_true_s, "pose_true", pose_true)
    if not (math.isfinite(rpe_delta_m) and rpe_delta_m > 0):
        raise ValueError(f"rpe_delta_m: {rpe_delta_m} must be a finite number > 0")
    inside = (t_est >= t_true[0]) & (t_est <= t_true[-1])
    if inside.sum() < 2:
        raise ValueError(
            f"t_est_s: only {int(inside.sum())} stamps lie inside the truth's span "
            f"[{t_true[0]:g}, {t_true[-1]:g}] s; need >= 2"
        )
    t_est, p_est = t_est[inside], p_est[inside].copy()
    q = se2.interpolate(t_true, p_true, t_est)
    if align:
        theta, shift = align_se2(p_est[:, :2], q[:, :2])
        c, s = math.cos(theta), math.sin(theta)
        p_est[:, :2] = p_est[:, :2] @ np.array([[c, s], [-s, c]]) + shift
        p_est[:, 2] = p_est[:, 2] + theta
    pos_err = np.hypot(*(p_est[:, :2] - q[:, :2]).T)
    yaw_err = np.abs(se2.wrap_rad(p_est[:, 2] - q[:, 2]))
    rpe_t, rpe_r = rpe(p_est, q, rpe_delta_m)
    return TrajectoryErrors(
        ate_m=float(np.sqrt(np.mean(pos_err**2))),
        rpe_trans_m=rpe_t,
        rpe_rot_deg=rpe_r,
        final_pos_err_m=float(pos_err[-1]),
        final_yaw_err_deg=float(np.degrees(yaw_err[-1])),
        rms_yaw_err_deg=float(np.degrees(np.sqrt(np.mean(yaw_err**2)))),
        max_yaw_err_deg=float(np.degrees(yaw_err.max())),
        length_m=float(np.sum(np.hypot(*np.diff(q[:, :2], axis=0).T))),
    )
