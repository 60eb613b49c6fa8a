"""The simulator's own interface on the graph, as gazebo_ros offers it, under the twin's node name: :class:`SimServices`.

``gazebo_msgs`` is not in Debian, so the calls are ``std_srvs/Empty`` services and standard message topics,
named after gazebo_ros' (which sit under ``/gazebo/``) but under the twin's node (``/amr_twin/...``;
``/r1/amr_twin/...`` with ``ROS_NAMESPACE=r1``; ``__name:=`` renames it):

- ``~pause_physics``: the twin holds at the pacer's next tick (no physics, no ``/clock``), still serving
  these calls and the graph's inputs (:meth:`amr_twin.live.pacer.Pacer.pause`); ``~unpause_physics`` runs it on;
- ``~reset_world``: the robot back at its start pose and the actors at the start of their paths, at rest
  (:meth:`amr_twin.sim.loop.Twin.reset_world`); ``~reset_simulation``: that, and the robot's own state (the
  wheels braked, the odometry at the origin of ``odom``: :meth:`~amr_twin.sim.loop.Twin.reset_simulation`).
  Simulated time runs on in both (Gazebo's ``reset_simulation`` rewinds it: a ROS 1 node seeing ``/clock``
  go back drops its tf buffers and timers);
- ``~set_pose`` (``geometry_msgs/PoseStamped``, frame ``map``, ``world`` or empty: the world frame): the robot
  teleported there at rest; a pose where it would overlap the world is refused (a warning) and it stays.

Each call returns once the twin has acted (at the pacer's next tick); one it refuses returns an error.
The robot's true pose and twist are on ``twin/ground_truth`` (``nav_msgs/Odometry``), the actors' on
``actors/poses`` (``geometry_msgs/PoseArray``, frame ``map``).
"""

from __future__ import annotations

import logging
import math

LOG = logging.getLogger(__name__)

SERVICES = ("pause_physics", "unpause_physics", "reset_world", "reset_simulation")
POSE_FRAMES = ("map", "world", "")
"""Frames a ``set_pose`` may be given in: the world frame (the twin's ``map`` is the world)."""


class SimServices:
    """Serve :data:`SERVICES` and take ``~set_pose`` for ``twin`` through ``pacer``, on the graph rospy joined."""

    def __init__(self, twin, pacer, rospy):
        from geometry_msgs.msg import PoseStamped
        from std_srvs.srv import Empty

        self.twin, self.pacer, self.rospy = twin, pacer, rospy
        self.refused = 0
        """``set_pose`` messages refused (each logged)."""
        acts = {"pause_physics": pacer.pause, "unpause_physics": pacer.resume,
                "reset_world": twin.reset_world, "reset_simulation": twin.reset_simulation}
        self.services = [rospy.Service("~" + name, Empty, self._handler(acts[name])) for name in SERVICES]
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
            LOG.warning("ros1: set_pose refused: frame %r (allowed: map, world or empty) with finite values",
                        msg.header.frame_id)
            return
        yaw = math.atan2(2 * (q.w * q.z + q.x * q.y), 1 - 2 * (q.y * q.y + q.z * q.z))
        try:
            self.pacer.post(lambda: self.twin.set_robot_pose(p.x, p.y, yaw))  # a refusal is logged by the pacer
        except RuntimeError:  # the twin has stopped
            pass

    def close(self) -> None:
        """Stop serving."""
        for service in self.services:
            service.shutdown()
        self.set_pose.unregister()
