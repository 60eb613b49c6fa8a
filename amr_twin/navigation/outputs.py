"""What the navigator shows the tools: the plan, the map, the local costmap and the footprint, as
ROS messages.

Published on the bus (the recordings and the live view take them from there, as a ROS graph's
``ros2 bag record`` would), frame ``map``:

- ``plan`` (``nav_msgs/Path``): every new plan;
- ``map`` (``nav_msgs/OccupancyGrid``, latched): the static map (100 occupied, 0 free, -1 unknown);
- ``local_costmap/costmap`` (``nav_msgs/OccupancyGrid``): a ``window_m`` square about the robot at
  ``costmap_hz``, the cost scaled as nav2's costmap_2d publishes it (254 -> 100, 253 -> 99, 1..252
  -> 1..98, 0 -> 0);
- ``local_costmap/published_footprint`` (``geometry_msgs/PolygonStamped``): the footprint at the
  estimated pose, at ``footprint_hz``.
"""

from __future__ import annotations

import numpy as np

from amr_twin.navigation.costmap import Costmap
from amr_twin.navigation.footprint import Footprint
from amr_twin.navigation.kinematics import to_map
from amr_twin.ros.geometry_messages import Point, Pose, Quaternion
from amr_twin.ros.messages import Header, Time
from amr_twin.ros.nav_messages import (
    MapMetaData,
    OccupancyGrid,
    Path,
    Point32,
    PolygonStamped,
    PoseStamped,
)

FRAME = "map"


def cost_to_grid(cost: np.ndarray) -> np.ndarray:
    """nav2's costmap_2d translation of costs (uint8) to OccupancyGrid values (int8)."""
    c = cost.astype(np.int32)
    out = np.where(c == 0, 0, 1 + (97 * (c - 1)) // 251)
    out = np.where(c == 253, 99, np.where(c == 254, 100, out))
    return np.where(c == 255, -1, out).astype(np.int8)


class NavOutputs:
    """Publishers of the navigator's plan, map, local costmap and footprint (module docstring)."""

    def __init__(
        self,
        bus,
        clock,
        costmap: Costmap,
        footprint: Footprint,
        window_m: float = 6.0,
        costmap_hz: float = 2.0,
        footprint_hz: float = 5.0,
    ):
        self.clock, self.costmap = clock, costmap
        self._plan = bus.advertise("plan", Path)
        self._local = bus.advertise("local_costmap/costmap", OccupancyGrid)
        self._fp = bus.advertise("local_costmap/published_footprint", PolygonStamped)
        self._corners = footprint.corners_xy_m()
        self._cells = int(round(window_m / costmap.resolution_m))
        self._costmap_us, self._footprint_us = int(1e6 / costmap_hz), int(1e6 / footprint_hz)
        self._next_costmap = self._next_fp = 0
        self._seq = 0
        static = costmap.static
        grid = np.where(static.occupied, 100, np.where(static.unknown, -1, 0)).astype(np.int8)
        bus.advertise("map", OccupancyGrid, latch=True).publish(
            self._grid(grid, static.origin_xy_m)
        )

    def _header(self) -> Header:
        self._seq += 1
        return Header(self._seq, Time.from_us(self.clock.now_us), FRAME)

    def _grid(self, data: np.ndarray, origin_xy) -> OccupancyGrid:
        h, w = data.shape
        info = MapMetaData(
            Time.from_us(self.clock.now_us),
            self.costmap.resolution_m,
            w,
            h,
            Pose(Point(float(origin_xy[0]), float(origin_xy[1]), 0.0), Quaternion()),
        )
        return OccupancyGrid(self._header(), info, data.reshape(-1))

    def plan(self, plan) -> None:
        """Publish a new plan."""
        head = self._header()
        poses = [
            PoseStamped(head, Pose(Point(float(x), float(y), 0.0), Quaternion.from_yaw(float(yaw))))
            for x, y, yaw in plan.poses
        ]
        self._plan.publish(Path(head, poses))

    def cycle(self, now_s: float, pose, costmap: Costmap) -> None:
        """Called every control cycle: the footprint and the local costmap when they are due."""
        now = self.clock.now_us
        if now >= self._next_fp:
            self._next_fp = now + self._footprint_us
            corners = to_map(np.asarray(pose, float)[None], self._corners)[0]
            self._fp.publish(
                PolygonStamped(
                    self._header(), [Point32(float(x), float(y), 0.0) for x, y in corners]
                )
            )
        if now >= self._next_costmap:
            self._next_costmap = now + self._costmap_us
            r, c, _ = costmap.cells(np.asarray(pose, float)[None, :2])
            n, (rows, cols) = self._cells, costmap.shape
            r0, c0 = (
                int(np.clip(r[0] - n // 2, 0, max(rows - n, 0))),
                int(np.clip(c[0] - n // 2, 0, max(cols - n, 0))),
            )
            window = self._window_cost(r0, c0, n)
            origin = costmap.origin_xy_m + np.array([c0, r0]) * costmap.resolution_m
            self._local.publish(self._grid(cost_to_grid(window), origin))

    def _window_cost(self, r0: int, c0: int, n: int) -> np.ndarray:
        from amr_twin.navigation.costmap import inflation_cost

        cm = self.costmap
        return inflation_cost(
            cm.dist_m[r0 : r0 + n, c0 : c0 + n],
            cm.inscribed_m,
            cm.inflation_radius_m,
            cm.cost_scaling_per_m,
        )
