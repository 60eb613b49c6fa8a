"""The support polygon of the robot's contacts with the floor, and how far inside it the centre of
mass is.

Plain geometry on the handful of support points (two wheels, four casters), in the
floor plane, m. Used by :mod:`amr_twin.model.statics` (the tip margin of ``amr-twin
model`` and of every sweep point).
"""

from __future__ import annotations

import numpy as np


def support_polygon(points_xy: np.ndarray) -> np.ndarray:
    """(k, 2) corners of the convex hull of ``points_xy`` ((n, 2), m), counter-clockwise.

    Andrew's monotone chain on the handful of support points (collinear points dropped):
    scipy's ``ConvexHull`` gives the same polygon (tests/model/test_statics.py checks it on
    random sets) but importing ``scipy.spatial`` cost 0.6 s of every ``amr-twin model`` and
    of every sweep process, for six points.
    """
    pts = sorted({(float(x), float(y)) for x, y in np.asarray(points_xy, float)})
    if len(pts) < 3:
        return np.array(pts, float).reshape(-1, 2)

    def cross(o, a, b):
        return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])

    lower, upper = [], []
    for p in pts:
        while len(lower) >= 2 and cross(lower[-2], lower[-1], p) <= 0:
            lower.pop()
        lower.append(p)
    for p in reversed(pts):
        while len(upper) >= 2 and cross(upper[-2], upper[-1], p) <= 0:
            upper.pop()
        upper.append(p)
    return np.array(lower[:-1] + upper[:-1], float)


def tip_margin_m(points_xy: np.ndarray, com_xy: np.ndarray) -> float:
    """Signed distance from ``com_xy`` to the nearest edge of the support polygon.

    Parameters
    ----------
    points_xy : (n, 2) support points in contact, m.
    com_xy : (2,) ground projection of the centre of mass, m.

    Returns
    -------
    float : positive inside the polygon, negative outside (the largest distance beyond an
    edge's line), m; ``-inf`` for fewer than three supports or supports in a line.
    """
    corners = support_polygon(points_xy)
    if len(corners) < 3:
        return -float("inf")
    edge = np.roll(corners, -1, axis=0) - corners  # counter-clockwise: the inside is on the left
    normal = (
        np.column_stack([edge[:, 1], -edge[:, 0]]) / np.hypot(edge[:, 0], edge[:, 1])[:, None]
    )  # outward
    return float(np.min(np.einsum("ij,ij->i", normal, corners - np.asarray(com_xy, float))))
