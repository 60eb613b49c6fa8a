"""The simulator's own interface on the graph, as gazebo_ros offers it, under the twin's node name:
:class:`SimServices`.

Reasons and measurements: docs/how-to/ros1.md#amr_twinros1sim_services."""

from __future__ import annotations

import logging
import math
from amr_twin.analysis.se2 import yaw_of_quaternion

LOG = logging.getLogger(__name__)

SERVICES = ("pause_physics", "unpause_physics", "reset_world", "reset_simulation")
POSE_FRAMES = ("map", "world", "")
"""Frames a ``set_pose`` may be given in: the world frame (the twin's ``map`` is the world)."""


class SimServices:
    """Serve :data:`SERVICES` and take ``~set_pose`` for ``twin`` through ``pacer``, on the graph
    rospy joined."""

    def __init__(self, twin, pacer, rospy):
        from geometry_msgs.msg import PoseStamped
        from std_srvs.srv import Empty

        self.twin, self.pacer, self.rospy = twin, pacer, rospy
        self.refused = 0
        """``set_pose`` messages refused (each logged)."""
        acts = {
            "pause_physics": pacer.pause,
            "unpause_physics": pacer.resume,
            "reset_world": twin.reset_world,
            "reset_simulation": twin.reset_simulation,
        }
        self.services = [
            rospy.Service("~" + name, Empty, self._handler(acts[name])) for name in SERVICES
        ]
        self.set_pose = rospy.Subscriber("~set_pose", PoseStamped, self._on_set_pose, queue_size=10)

    def _handler(self, act):
        from std_srvs.srv import EmptyResponse

        def handle(_request):
            try:
                self.pacer.call(act)
            except Exception as exc:  # noqa: BLE001 - the caller gets it as the service's error
                raise self.rospy.ServiceException(str(exc)) from None
            return EmptyResponse()

        return handle

    def _on_set_pose(self, msg) -> None:
        p, q = msg.pose.position, msg.pose.orientation
        values = (p.x, p.y, q.x, q.y, q.z, q.w)
        frame = msg.header.frame_id.lstrip("/")
        if frame not in POSE_FRAMES or not all(math.isfinite(v) for v in values):
            self.refused += 1
            LOG.warning(
                "ros1: set_pose refused: frame %r (allowed: map, world or empty) with finite "
                "values",
                msg.header.frame_id,
            )
            return
        yaw = yaw_of_quaternion(q.w, q.x, q.y, q.z)
        try:
            self.pacer.post(
                lambda: self.twin.set_robot_pose(p.x, p.y, yaw)
            )  # a refusal is logged by the pacer
        except RuntimeError:  # the twin has stopped
            pass

    def close(self) -> None:
        """Stop serving."""
        for service in self.services:
            service.shutdown()
        self.set_pose.unregister()
