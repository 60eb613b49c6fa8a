"""``map -> odom`` on ``/tf`` (REP-105) from the localisation's pose in ``map``:
:class:`MapTransform`.

The wheel odometry gives ``odom -> base_link``; a localisation that knows the robot in ``map`` (the
navigation stack's EKF of odometry, gyro and UWB on ``odometry/filtered``, or the ground truth on
``ground_truth/odom``, both in frame ``map``) gives ``map -> base_link``. What a ROS 1 localiser
(amcl, robot_localization's map instance) publishes is the difference, ``map -> odom = (map ->
base_link) * (odom -> base_link)^-1``, so that ``map -> base_link`` resolves through the tree. The
EKF publishes at the stamp of each odometry message, just after it (the bus hands the odometry to
the bridge first), so both poses are of the same instant; the ground truth's is taken with the
newest odometry at or before it (at 0.5 m/s, 10 ms off is 5 mm).

Written on the first map pose at or after each multiple of :data:`PERIOD_US` (25 Hz: amcl's default
``transform_tolerance`` of 0.1 s is 2.5 periods), only while ``/tf`` has a subscriber; the first
source to publish in ``map`` is kept.
"""

from __future__ import annotations

import math
import struct

from amr_twin.ros.ros_state import MAP_FRAME
from amr_twin.ros.tf_buffer import ODOM_FRAME
from amr_twin.analysis.se2 import yaw_of_quaternion

SOURCES = ("odometry/filtered", "ground_truth/odom")
"""Bus topics of a pose in ``map`` (``nav_msgs/Odometry``): localisations of
:mod:`amr_twin.navigation.localisation`."""
ODOM_TOPIC = "odom"
PERIOD_US = 40_000
"""Simulated time between two ``map -> odom`` messages, us (25 Hz: every other 50 Hz odometry
message)."""


def _string(text: str) -> bytes:
    data = text.encode()
    return struct.pack("<I", len(data)) + data


class MapTransform:
    """Follows the odometry and the localisation's pose on the bus; :meth:`take` gives ``map ->
    odom`` when due.

    ``parent`` and ``child`` are the frames written (``map``, ``odom``)."""

    TOPICS = frozenset((ODOM_TOPIC, *SOURCES))

    def __init__(
        self, parent: str = MAP_FRAME, child: str = ODOM_FRAME, period_us: int = PERIOD_US
    ):
        self.period_us = int(period_us)
        self.source: str | None = None
        """The bus topic the map pose is taken from (the first to publish one in ``map``)."""
        self.sent = 0
        """``map -> odom`` messages given so far."""
        self._odom: tuple[float, float, float] | None = None
        self._next_us = 0
        self._frames = struct.Struct(f"<IIII{len(_string(parent)) + len(_string(child))}s7d")
        self._names = _string(parent) + _string(child)

    def take(self, topic: str, msg) -> tuple[int, bytes] | None:
        """A message of ``topic`` (one of :attr:`TOPICS`): ``(stamp_us, tf2_msgs/TFMessage bytes)``
        of ``map -> odom`` when one is due, else None."""
        p = msg.pose.pose
        q = p.orientation
        yaw = yaw_of_quaternion(q.w, q.x, q.y, q.z)
        if topic == ODOM_TOPIC:
            self._odom = (p.position.x, p.position.y, yaw)
            return None
        if self._odom is None or msg.header.frame_id != MAP_FRAME:
            return None
        if self.source is None:
            self.source = topic
        elif topic != self.source:
            return None
        stamp = msg.header.stamp
        t_us = stamp.sec * 1_000_000 + stamp.nanosec // 1000
        if t_us < self._next_us:
            return None
        self._next_us = (t_us // self.period_us + 1) * self.period_us
        x, y, yaw_rad = _map_from_odom((p.position.x, p.position.y, yaw), self._odom)
        self.sent += 1
        half = 0.5 * yaw_rad
        return t_us, self._frames.pack(
            1,
            0,
            stamp.sec,
            stamp.nanosec,
            self._names,
            x,
            y,
            0.0,
            0.0,
            0.0,
            math.sin(half),
            math.cos(half),
        )


def _map_from_odom(map_base, odom_base) -> tuple[float, float, float]:
    """``map -> odom`` (x_m, y_m, yaw_rad) from ``map -> base_link`` and ``odom -> base_link``."""
    mx, my, myaw = map_base
    ox, oy, oyaw = odom_base
    yaw = myaw - oyaw
    c, s = math.cos(yaw), math.sin(yaw)
    return mx - (c * ox - s * oy), my - (s * ox + c * oy), math.atan2(math.sin(yaw), math.cos(yaw))
