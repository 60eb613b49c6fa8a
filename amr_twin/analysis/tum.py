"""Planar trajectories as TUM files, the format evo, rpg_trajectory_evaluation and the TUM RGB-D
tools read.

A TUM trajectory is a text file with one pose per line::

    timestamp tx ty tz qx qy qz qw

(seconds, metres, a unit quaternion; Sturm et al., IROS 2012, and evo's ``tum`` format).
The twin's poses are planar ``(N, 3)`` arrays ``[x_m, y_m, yaw_rad]``: written with
``tz = 0`` and the quaternion of a rotation about z. Stamps are written with 6 decimals
(the twin's clock counts microseconds, so nothing is rounded).

:func:`truth_at` samples the true trajectory at the union of its own stamps and every
estimate's (linear interpolation between record samples, yaw unwrapped, as
:func:`amr_twin.analysis.trajectory.errors` does), so that a tool associating stamps by nearest
neighbour (evo's ``--t_max_diff``) pairs every estimate pose with the true pose of its
own instant and scores what :mod:`amr_twin.analysis.trajectory` scores.
"""

from __future__ import annotations

from pathlib import Path
from typing import Iterable

import numpy as np

from amr_twin.analysis import se2

from amr_twin.base import atomic_file

HEADER = "# timestamp tx ty tz qx qy qz qw\n"


def text(t_s: np.ndarray, pose: np.ndarray) -> str:
    """TUM lines of stamps ``t_s (N,)`` s and planar poses ``pose (N, 3)`` (``[x_m, y_m,
    yaw_rad]``)."""
    t = np.asarray(t_s, dtype=float).ravel()
    p = np.asarray(pose, dtype=float).reshape(-1, 3)
    if p.shape[0] != t.shape[0]:
        raise ValueError(f"pose: {p.shape[0]} rows, expected one per stamp ({t.shape[0]})")
    if not (np.isfinite(t).all() and np.isfinite(p).all()):
        raise ValueError("t_s, pose: every value must be finite")
    half = 0.5 * p[:, 2]
    rows = np.column_stack(
        [
            t,
            p[:, 0],
            p[:, 1],
            np.zeros_like(t),
            np.zeros_like(t),
            np.zeros_like(t),
            np.sin(half),
            np.cos(half),
        ]
    )
    body = "\n".join(
        f"{r[0]:.6f} {r[1]:.6f} {r[2]:.6f} {r[3]:.1f} {r[4]:.1f} {r[5]:.1f} {r[6]:.9f} {r[7]:.9f}"
        for r in rows
    )
    return HEADER + body + ("\n" if len(rows) else "")


def write(path: Path, t_s: np.ndarray, pose: np.ndarray) -> None:
    """Write a TUM file atomically (temporary name, then rename)."""
    atomic_file.write_text(Path(path), text(t_s, pose))


def read(path: Path) -> tuple[np.ndarray, np.ndarray]:
    """Stamps ``(N,)`` s and planar poses ``(N, 3)`` of a TUM file (yaw from the quaternion about
    z)."""
    rows = np.loadtxt(path, comments="#", ndmin=2)
    if rows.shape[1] != 8:
        raise ValueError(
            f"{path}: {rows.shape[1]} columns per line, a TUM file has 8 "
            "(timestamp tx ty tz qx qy qz qw)"
        )
    yaw = se2.yaws_of_quaternions(rows[:, [7, 4, 5, 6]])  # TUM's qx qy qz qw as w, x, y, z
    return rows[:, 0], np.column_stack([rows[:, 1], rows[:, 2], yaw])


def truth_at(
    t_true_s: np.ndarray, pose_true: np.ndarray, stamps: Iterable[np.ndarray]
) -> tuple[np.ndarray, np.ndarray]:
    """The truth at its own stamps and at every stamp of ``stamps`` inside its span.

    Returns stamps ``(M,)`` s, sorted and unique to the microsecond, and poses ``(M, 3)``.
    """
    t_true = np.asarray(t_true_s, dtype=float)
    us = [np.round(t_true * 1e6).astype(np.int64)]
    for t in stamps:
        t = np.asarray(t, dtype=float)
        t = t[(t >= t_true[0]) & (t <= t_true[-1])]
        us.append(np.round(t * 1e6).astype(np.int64))
    t_all = np.unique(np.concatenate(us)) / 1e6
    return t_all, se2.interpolate(t_true, pose_true, t_all).reshape(-1, 3)
