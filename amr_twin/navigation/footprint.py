"""The robot's footprint: the rectangle its body and wheels cover on the floor, in ``base_link``.

From the model's parameters (``models/amr/amr.yaml``): the chassis frame is ``chassis.length_m``
long and centred on the axle (``base_link``'s origin), and the drive wheels stick out sideways to
``wheel.separation_m / 2 + wheel.width_m / 2``; the LiDAR on the front border stays within the
frame's length. nav2 takes a polygon ``footprint`` and derives the same two radii:
the *inscribed* radius (a circle about the origin inside the footprint: the centre closer than
this to an obstacle is a collision whatever the heading) and the *circumscribed* one (farther
than this is free whatever the heading).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Footprint:
    """A rectangle ``[x_min, x_max] x [-half_width, half_width]`` in ``base_link``, m."""

    x_min_m: float
    x_max_m: float
    half_width_m: float

    @property
    def inscribed_radius_m(self) -> float:
        """Radius of the largest circle about ``base_link``'s origin inside the footprint, m."""
        return min(self.half_width_m, -self.x_min_m, self.x_max_m)

    @property
    def circumscribed_radius_m(self) -> float:
        """Radius of the smallest circle about the origin holding the footprint, m."""
        return math.hypot(max(-self.x_min_m, self.x_max_m), self.half_width_m)

    def padded(self, pad_m: float) -> Footprint:
        """The footprint grown by ``pad_m`` on every side."""
        return Footprint(self.x_min_m - pad_m, self.x_max_m + pad_m, self.half_width_m + pad_m)

    def corners_xy_m(self) -> np.ndarray:
        """Corners (4, 2) in ``base_link``, counter-clockwise from rear right, m."""
        x0, x1, h = self.x_min_m, self.x_max_m, self.half_width_m
        return np.array([[x0, -h], [x1, -h], [x1, h], [x0, h]])

    def outline_xy_m(self, spacing_m: float) -> np.ndarray:
        """Points (K, 2) every ``spacing_m`` or less along the outline, in ``base_link``, m."""
        c = self.corners_xy_m()
        pts = []
        for a, b in zip(c, np.roll(c, -1, axis=0)):
            n = max(1, int(math.ceil(np.hypot(*(b - a)) / spacing_m)))
            pts.append(a + np.arange(n)[:, None] / n * (b - a))
        return np.vstack(pts)

    def distance_m(self, xy_m: np.ndarray) -> np.ndarray:
        """Distance (K,) from points (K, 2) in ``base_link`` to the rectangle (0 inside), m."""
        xy = np.asarray(xy_m, float).reshape(-1, 2)
        cx, hx = 0.5 * (self.x_max_m + self.x_min_m), 0.5 * (self.x_max_m - self.x_min_m)
        dx = np.maximum(np.abs(xy[:, 0] - cx) - hx, 0.0)
        dy = np.maximum(np.abs(xy[:, 1]) - self.half_width_m, 0.0)
        return np.hypot(dx, dy)

    def contains(self, xy_m: np.ndarray) -> np.ndarray:
        """Which points (K, 2) in ``base_link`` lie inside the rectangle, (K,) bool."""
        xy = np.asarray(xy_m, float).reshape(-1, 2)
        return (
            (xy[:, 0] >= self.x_min_m)
            & (xy[:, 0] <= self.x_max_m)
            & (np.abs(xy[:, 1]) <= self.half_width_m)
        )


def robot_footprint(cfg) -> Footprint:
    """The footprint of the robot of ``cfg`` (a :class:`~amr_twin.model.config.TwinConfig`)."""
    half_length = cfg.chassis.length_m / 2
    return Footprint(-half_length, half_length, cfg.half_width_m)
