"""Wheel odometry node: ``wheel0_Vel``/``wheel1_Vel`` to ``nav_msgs/Odometry`` on ``odom``.

The firmware publishes each wheel's speed in RPM as measured on the driver's SC
output, which has no direction (§3.2.3). The sign is taken from the last
``wheel_Command`` motion code of that wheel (1 forward, -1 backward, 0 brake:
speed taken as 0). With ``signed_input=True`` the wheel topics are read as
signed RPM and ``wheel_Command`` is ignored; :meth:`WheelOdometry.set_wheel_speeds_rpm`
feeds signed speeds directly.

Wheel speeds are held constant between messages and the pose is integrated
exactly along the arc they define (no Euler error), each time a speed changes and
at each publication. ``odom`` (frame ``odom``, child ``base_link``, REP-105) and
the ``odom -> base_link`` transform are published at ``publish_rate_hz`` on clock
events.

Known limits, inherited from the hardware: the firmware publishes a speed only
after a full wheel revolution, so a wheel that stops without a brake command
keeps its last speed; a motion sign change is applied at command time while the
wheel is still spinning the old way.
"""

from __future__ import annotations

import math
from typing import Sequence

import numpy as np

from amr_twin.bus import BASE_FRAME, ODOM_FRAME, Bus
from amr_twin.clock import VirtualClock
from amr_twin.messages import (Float64, Float64MultiArray, Header, Odometry, Point, Pose,
                               PoseWithCovariance, Quaternion, Time, Transform,
                               TransformStamped, Twist, TwistWithCovariance, Vector3)

from .wheel_command import WHEEL_RADIUS_M

WHEEL_SEPARATION_M = 0.48
"""``L`` of listing 4.2."""
DEFAULT_COVARIANCE_DIAGONAL = (1e-3, 1e-3, 1e6, 1e6, 1e6, 1e3)
"""(x, y, z, roll, pitch, yaw) variances, the ros_controllers diff_drive example values."""


def _covariance(diagonal: Sequence[float]) -> np.ndarray:
    if len(diagonal) != 6:
        raise ValueError(f"a covariance diagonal has 6 values, got {len(diagonal)}")
    return np.diag(np.asarray(diagonal, dtype=np.float64)).ravel()


class WheelOdometry:
    """Dead reckoning from the wheel speeds, published on ``odom`` and tf.

    Parameters
    ----------
    bus, clock : Bus, VirtualClock
        Shared bus and clock.
    wheel_radius_m, wheel_separation_m : float
        Nominal geometry, m (thesis: 0.125 and 0.48).
    wheel_radius_multiplier, left_radius_multiplier, right_radius_multiplier : float
        Calibration factors of the radii (global, then per wheel).
    wheel_separation_multiplier : float
        Calibration factor of the separation.
    publish_rate_hz : float
        Rate of ``odom`` and tf, Hz.
    pose_covariance_diagonal, twist_covariance_diagonal : sequence of 6 float
        Variances of (x, y, z, rot x, rot y, rot z), SI units squared.
    signed_input : bool
        Read the wheel topics as signed RPM (a firmware that knows the sign).
    publish_tf : bool
        Also broadcast ``odom -> base_link``.
    """

    def __init__(self, bus: Bus, clock: VirtualClock, wheel_radius_m: float = WHEEL_RADIUS_M,
                 wheel_separation_m: float = WHEEL_SEPARATION_M,
                 wheel_radius_multiplier: float = 1.0, left_radius_multiplier: float = 1.0,
                 right_radius_multiplier: float = 1.0, wheel_separation_multiplier: float = 1.0,
                 publish_rate_hz: float = 50.0,
                 pose_covariance_diagonal: Sequence[float] = DEFAULT_COVARIANCE_DIAGONAL,
                 twist_covariance_diagonal: Sequence[float] = DEFAULT_COVARIANCE_DIAGONAL,
                 signed_input: bool = False, publish_tf: bool = True,
                 frame_id: str = ODOM_FRAME, child_frame_id: str = BASE_FRAME):
        if publish_rate_hz <= 0:
            raise ValueError(f"publish_rate_hz must be positive, got {publish_rate_hz}")
        self.bus, self.clock = bus, clock
        radius_m = wheel_radius_m * wheel_radius_multiplier
        self.left_radius_m = radius_m * left_radius_multiplier
        self.right_radius_m = radius_m * right_radius_multiplier
        self.separation_m = wheel_separation_m * wheel_separation_multiplier
        self.period_us = int(round(1e6 / publish_rate_hz))
        self.pose_covariance = _covariance(pose_covariance_diagonal)
        self.twist_covariance = _covariance(twist_covariance_diagonal)
        self.signed_input, self.publish_tf = signed_input, publish_tf
        self.frame_id, self.child_frame_id = frame_id, child_frame_id
        self.x_m = self.y_m = self.yaw_rad = 0.0
        self._rpm_magnitude = [0.0, 0.0]
        self._motion = [0, 0]
        self._signed_rpm = [0.0, 0.0]
        self._last_us = clock.now_us
        self._seq = 0
        self._pub = bus.advertise("odom", Odometry)
        self._subs = [bus.subscribe("wheel0_Vel", lambda m: self._on_speed(0, m)),
                      bus.subscribe("wheel1_Vel", lambda m: self._on_speed(1, m))]
        if not signed_input:
            self._subs.append(bus.subscribe("wheel_Command", self._on_command))
        self._timer = clock.schedule_in(self.period_us, self._on_timer)

    # -- inputs -----------------------------------------------------------------
    def _on_speed(self, wheel: int, msg: Float64) -> None:
        if self.signed_input:
            speeds = list(self._signed_rpm)
            speeds[wheel] = msg.data
            self.set_wheel_speeds_rpm(*speeds)
        else:
            self._rpm_magnitude[wheel] = abs(msg.data)
            self._apply_signs()

    def _on_command(self, msg: Float64MultiArray) -> None:
        self._motion = [int(msg.data[0]), int(msg.data[2])]
        self._apply_signs()

    def _apply_signs(self) -> None:
        rpm = [float(np.sign(m)) * s for m, s in zip(self._motion, self._rpm_magnitude)]
        self.set_wheel_speeds_rpm(*rpm)

    def set_wheel_speeds_rpm(self, left_rpm: float, right_rpm: float) -> None:
        """Signed wheel speeds from now on (forward positive), RPM."""
        self.update()
        self._signed_rpm = [float(left_rpm), float(right_rpm)]

    # -- state ------------------------------------------------------------------
    def body_velocity(self) -> tuple[float, float]:
        """Current forward speed (m/s) and yaw rate (rad/s, CCW +) of ``base_link``."""
        v_left = self._signed_rpm[0] * 2.0 * math.pi / 60.0 * self.left_radius_m
        v_right = self._signed_rpm[1] * 2.0 * math.pi / 60.0 * self.right_radius_m
        return 0.5 * (v_left + v_right), (v_right - v_left) / self.separation_m

    def update(self) -> None:
        """Integrate the pose from the last update to ``clock.now_us`` along the arc."""
        dt_s = (self.clock.now_us - self._last_us) * 1e-6
        self._last_us = self.clock.now_us
        if dt_s <= 0.0:
            return
        v_m_s, w_rad_s = self.body_velocity()
        dyaw_rad = w_rad_s * dt_s
        yaw0 = self.yaw_rad
        if abs(dyaw_rad) < 1e-9:
            mid = yaw0 + 0.5 * dyaw_rad
            self.x_m += v_m_s * dt_s * math.cos(mid)
            self.y_m += v_m_s * dt_s * math.sin(mid)
        else:
            radius_m = v_m_s / w_rad_s
            self.x_m += radius_m * (math.sin(yaw0 + dyaw_rad) - math.sin(yaw0))
            self.y_m -= radius_m * (math.cos(yaw0 + dyaw_rad) - math.cos(yaw0))
        self.yaw_rad = math.atan2(math.sin(yaw0 + dyaw_rad), math.cos(yaw0 + dyaw_rad))

    def reset(self, x_m: float = 0.0, y_m: float = 0.0, yaw_rad: float = 0.0) -> None:
        """Set the pose in ``odom``."""
        self.update()
        self.x_m, self.y_m, self.yaw_rad = float(x_m), float(y_m), float(yaw_rad)

    # -- output -----------------------------------------------------------------
    def _on_timer(self) -> None:
        self._timer = self.clock.schedule_in(self.period_us, self._on_timer)
        self.publish()

    def publish(self) -> Odometry:
        """Integrate to now, publish ``odom`` (and tf) and return the message."""
        self.update()
        stamp = Time.from_us(self.clock.now_us)
        v_m_s, w_rad_s = self.body_velocity()
        orientation = Quaternion.from_yaw(self.yaw_rad)
        msg = Odometry(
            header=Header(self._seq, stamp, self.frame_id), child_frame_id=self.child_frame_id,
            pose=PoseWithCovariance(Pose(Point(self.x_m, self.y_m, 0.0), orientation),
                                    self.pose_covariance.copy()),
            twist=TwistWithCovariance(Twist(Vector3(v_m_s, 0.0, 0.0), Vector3(0.0, 0.0, w_rad_s)),
                                      self.twist_covariance.copy()))
        self._seq += 1
        self._pub.publish(msg)
        if self.publish_tf:
            self.bus.send_transform(TransformStamped(
                Header(0, stamp, self.frame_id), self.child_frame_id,
                Transform(Vector3(self.x_m, self.y_m, 0.0), orientation)))
        return msg

    def shutdown(self) -> None:
        """Stop publishing and unsubscribe."""
        self._timer.cancel()
        for sub in self._subs:
            sub.unregister()
