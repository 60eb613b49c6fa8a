"""Where the robots of a world start and what their names begin with.

A world holds one robot or a fleet of up to :data:`MAX_ROBOTS`. The lone robot's names begin
with :data:`ROBOT_PREFIX` (``amr/base_link``); a fleet's robot ``i`` (1-based) with ``amr-i/``
(:func:`fleet_starts`), its serial number. The model build (:func:`amr_twin.model.build.build`)
attaches one copy of the robot per :class:`RobotStart`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

ROBOT_PREFIX = "amr/"
"""Prefix of the lone robot's names in the compiled model."""
MAX_ROBOTS = 20
"""Most robots one world holds."""


@dataclass(frozen=True)
class RobotStart:
    """One robot of a world: its name prefix (``amr-2/``) and start pose x_m, y_m, yaw_rad (world
    frame, REP-103)."""

    prefix: str
    x_m: float
    y_m: float
    yaw_rad: float

    @property
    def name(self) -> str:
        """The robot's name: its prefix without the slash (``amr-2``)."""
        return self.prefix.rstrip("/")


def fleet_starts(poses) -> tuple[RobotStart, ...]:
    """The :class:`RobotStart` of each pose ``(x_m, y_m, yaw_rad)`` in ``poses``: one pose, the lone
    robot (:data:`ROBOT_PREFIX`); several, ``amr-1/`` ... ``amr-N/`` in order. ValueError (one
    line) for no pose, more than :data:`MAX_ROBOTS`, or a pose that is not three finite numbers."""
    poses = [tuple(p) for p in poses]
    if not 1 <= len(poses) <= MAX_ROBOTS:
        raise ValueError(f"robots: {len(poses)} start poses; 1 to {MAX_ROBOTS} allowed")
    for i, pose in enumerate(poses, 1):
        if len(pose) != 3 or not all(
            isinstance(v, (int, float)) and math.isfinite(v) for v in pose
        ):
            raise ValueError(
                f"robots: start {i} is {pose!r}; three finite numbers x_m, y_m, yaw_rad"
            )
    if len(poses) == 1:
        return (RobotStart(ROBOT_PREFIX, *map(float, poses[0])),)
    return tuple(RobotStart(f"amr-{i}/", *map(float, p)) for i, p in enumerate(poses, 1))


def overlapping_starts(poses, half_length_m: float, half_width_m: float) -> tuple[int, int] | None:
    """The first pair ``(i, j)`` (0-based, i < j) of ``poses`` (x_m, y_m, yaw_rad) whose robots'
    footprints (rectangles of ``half_length_m`` by ``half_width_m`` about the base, m) overlap;
    None when no two do. A separating-axis test on the four edge directions."""
    boxes = []
    for x, y, yaw in poses:
        c, s = math.cos(yaw), math.sin(yaw)
        axes = ((c, s), (-s, c))
        corners = [
            (
                x + a * half_length_m * c - b * half_width_m * s,
                y + a * half_length_m * s + b * half_width_m * c,
            )
            for a, b in ((1, 1), (1, -1), (-1, -1), (-1, 1))
        ]
        boxes.append((axes, corners))
    for i, (axes_i, corners_i) in enumerate(boxes):
        for j in range(i + 1, len(boxes)):
            axes_j, corners_j = boxes[j]
            if all(
                min(ux * px + uy * py for px, py in corners_i)
                < max(ux * px + uy * py for px, py in corners_j)
                and min(ux * px + uy * py for px, py in corners_j)
                < max(ux * px + uy * py for px, py in corners_i)
                for ux, uy in axes_i + axes_j
            ):
                return i, j
    return None
