"""Ground truth on the bus, as Gazebo's p3d plugin gives it: the robot's true pose and twist.

A perfect localiser for studies that must not depend on an estimator (a planner's or a
controller's): ``nav_msgs/Odometry`` on ``ground_truth/odom`` at ``rate_hz``, frame ``map`` (the
world frame), child ``base_link``, the twist in ``base_link`` (forward speed, yaw rate), zero
covariances. A synced clock event reads the physics' base pose and velocity at its instant.
"""

from __future__ import annotations

import math

from amr_twin.ros.geometry_messages import (
    Odometry,
    Point,
    Pose,
    PoseWithCovariance,
    Quaternion,
    Twist,
    TwistWithCovariance,
    Vector3,
)
from amr_twin.ros.messages import Header, Time

TOPIC = "ground_truth/odom"


class GroundTruth:
    """Publish the true pose of ``physics`` (:class:`~amr_twin.sim.physics.Physics`) every ``1 /
    rate_hz`` s."""

    def __init__(self, physics, clock, bus, rate_hz: float = 50.0):
        if not (math.isfinite(rate_hz) and 0 < rate_hz <= 1000):
            raise ValueError(f"rate_hz: {rate_hz} must be in (0, 1000] Hz")
        self.physics, self.clock = physics, clock
        self._pub = bus.advertise(TOPIC, Odometry)
        self._seq = 0
        self._handle = clock.schedule_every(clock.now_us, int(round(1e6 / rate_hz)), self._tick)

    def _tick(self) -> None:
        p = self.physics.pose()
        vel = self.physics.base_velocity()  # linear in the world, angular in the body
        c, s = math.cos(p.yaw_rad), math.sin(p.yaw_rad)
        self._seq += 1
        self._pub.publish(
            Odometry(
                header=Header(self._seq, Time.from_us(self.clock.now_us), "map"),
                child_frame_id="base_link",
                pose=PoseWithCovariance(
                    Pose(Point(p.x_m, p.y_m, 0.0), Quaternion.from_yaw(p.yaw_rad))
                ),
                twist=TwistWithCovariance(
                    Twist(
                        Vector3(c * vel[0] + s * vel[1], 0.0, 0.0), Vector3(0.0, 0.0, float(vel[5]))
                    )
                ),
            )
        )

    def stop(self) -> None:
        self._handle.cancel()
