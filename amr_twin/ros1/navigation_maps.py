"""The navigator's maps on the ROS 1 graph, as map_server and move_base publish them:
:class:`NavigationMaps`.

Relative names (under the twin's namespace), frame ``map``:

- ``map`` (``nav_msgs/OccupancyGrid``, latched): the static map (100 occupied, 0 free, -1 unknown),
as
  map_server publishes it;
- ``move_base/global_costmap/costmap`` (``nav_msgs/OccupancyGrid``): the whole costmap (static, what
the
  scans marked, inflation) in costmap_2d's values, every :data:`GLOBAL_PERIOD_US` while someone
  subscribes;
- ``move_base/local_costmap/costmap``: the navigator's window about the robot
  (:mod:`amr_twin.navigation.outputs`, 2 Hz while a goal is active).

Everything here runs in the twin's thread (its hooks and the pacer's ticks).
"""

from __future__ import annotations

import warnings

import numpy as np

from amr_twin.navigation.outputs import cost_to_grid
from amr_twin.ros.geometry_messages import Point, Pose, Quaternion
from amr_twin.ros.messages import Header, Time
from amr_twin.ros.nav_messages import MapMetaData, OccupancyGrid

GLOBAL_PERIOD_US = 1_000_000
"""Period of the global costmap, simulated us (costmap_2d's ``publish_frequency`` 1 Hz of
move_base's examples)."""
LOCAL_TOPIC = "local_costmap/costmap"
MAP_FRAME = "map"


class NavigationMaps:
    """Publishers of ``navigator``'s map and costmaps (module docstring)."""

    def __init__(self, twin, navigator):
        from amr_twin.ros1.messages import Ros1Messages

        self.conv = conv = Ros1Messages()
        rospy = conv.rospy
        self.twin, self.nav = twin, navigator
        grid_cls = conv.ros_class("nav_msgs/OccupancyGrid")
        with warnings.catch_warnings():  # a latched map without a queue: published once
            warnings.simplefilter("ignore")
            self.map_pub = rospy.Publisher("map", grid_cls, latch=True, queue_size=None)
        self.global_pub = rospy.Publisher(
            "move_base/global_costmap/costmap", grid_cls, queue_size=2
        )
        self.local_pub = rospy.Publisher("move_base/local_costmap/costmap", grid_cls, queue_size=2)
        static = navigator.costmap.static
        grid = np.where(static.occupied, 100, np.where(static.unknown, -1, 0)).astype(np.int8)
        self.map_pub.publish(conv.to_ros(self._grid(grid, static.origin_xy_m, twin.clock.now_us)))
        self._next_global_us = 0
        twin.on_message(self._on_local, (LOCAL_TOPIC,))

    def _grid(self, data: np.ndarray, origin_xy, t_us: int) -> OccupancyGrid:
        cm = self.nav.costmap
        stamp = Time.from_us(t_us)
        h, w = data.shape
        info = MapMetaData(
            stamp,
            cm.resolution_m,
            w,
            h,
            Pose(Point(float(origin_xy[0]), float(origin_xy[1]), 0.0), Quaternion()),
        )
        return OccupancyGrid(Header(0, stamp, MAP_FRAME), info, data.reshape(-1))

    def _on_local(self, _topic: str, msg, _t_us: int) -> None:
        if self.local_pub.get_num_connections():
            self.local_pub.publish(self.conv.to_ros(msg))

    def flush(self, t_us: int) -> None:
        """At a pacer tick: the global costmap when it is due and someone subscribes."""
        if t_us < self._next_global_us or not self.global_pub.get_num_connections():
            return
        self._next_global_us = t_us + GLOBAL_PERIOD_US
        cm = self.nav.costmap
        self.global_pub.publish(
            self.conv.to_ros(self._grid(cost_to_grid(cm.cost()), cm.origin_xy_m, t_us))
        )

    def close(self) -> None:
        """Stop publishing."""
        self.twin.unhook(self._on_local)
        for pub in (self.map_pub, self.global_pub, self.local_pub):
            pub.unregister()
