"""Wheel odometry node: ``wheel0_Vel``/``wheel1_Vel`` to ``nav_msgs/Odometry`` on ``odom``.

Each wheel's speed estimate is built from the firmware's samples, signed by the ``wheel_Command``
motion codes (:mod:`amr_twin.controllers.wheel_speed_samples`: what a sample means,
``speed_samples``). With ``signed_input=True`` the wheel topics are read as signed RPM and
``wheel_Command`` is ignored;
:meth:`WheelOdometry.set_wheel_speeds_rpm` feeds signed speeds directly.

Two poses (REP-105: ``odom -> base_link`` must be continuous): the *smoothed* pose corrects the past
a window describes (it jumps when a sample arrives); the *published* one is integrated forward only,
never revised (:mod:`amr_twin.estimation.published_pose`). ``odom`` (frame ``odom``, child
``base_link``) and the ``odom -> base_link`` transform are published at ``publish_rate_hz``, the
first at the node's start.

Reasons and measurements: docs/explanation/fusion.md#amr_twincontrollersodometry."""

from __future__ import annotations

import math
from typing import Sequence


from amr_twin.ros.bus import Bus
from amr_twin.ros.geometry_messages import (
    Odometry,
)
from amr_twin.ros.messages import Float64, Float64MultiArray
from amr_twin.ros.tf_buffer import BASE_FRAME, ODOM_FRAME
from amr_twin.base.clock import VirtualClock
from amr_twin.estimation.drive_arcs import DriveGeometry
from amr_twin.estimation.published_pose import PublishedPose
from amr_twin.controllers.odometry_message import (
    DEFAULT_COVARIANCE_DIAGONAL,
    covariance,
    odometry_message,
)
from amr_twin.controllers.wheel_speed_samples import WheelSpeedSamples


class WheelOdometry:
    """Dead reckoning from the wheel speeds, published on ``odom`` and tf.

    Args (SI units unless named; in full:
    docs/explanation/fusion.md#amr_twincontrollersodometrywheelodometry):
        bus, clock: the shared bus and clock.
        wheel_radius_m, wheel_separation_m: nominal geometry (thesis 0.125, listing 4.2's 0.48).
        wheel_radius_multiplier, left_radius_multiplier, right_radius_multiplier,
        wheel_separation_multiplier: calibration factors (global, then per wheel; the separation).
        publish_rate_hz: rate of ``odom`` and tf, Hz.
        pose_covariance_diagonal, twist_covariance_diagonal: variances of (x, y, z, rot x, y, z).
        signed_input: read the wheel topics as signed RPM. publish_tf: also broadcast the transform.
        speed_samples: ``"window"`` or ``"hold"``, what a speed sample means (module docstring).
        revolutions_per_sample: revolutions one ``"window"`` sample measures (thesis: 1).
        sample_latency_s: measurement end to receipt (~1.4 ms). max_substep_s: longest arc.
        brake_stop_s, brake_friction_rpm_s: a fast braked wheel's stop time; a slow one's RPM/s.
        catchup_time_s (> 0), catchup_max_fraction (>= 0): how a pose difference is made up.
        max_wheel_accel_m_s2: fastest wheel speed change the pose follows, at the rim (inf: none).
        sample_gap_s: the firmware's longest wait between samples (``inf``: no silence bound).
        rest_rpm: slowest speed a silent wheel is believed to turn at. start_s: a start's ramp.
    """

    def __init__(
        self,
        bus: Bus,
        clock: VirtualClock,
        *,
        wheel_radius_m: float,
        wheel_separation_m: float,
        wheel_radius_multiplier: float = 1.0,
        left_radius_multiplier: float = 1.0,
        right_radius_multiplier: float = 1.0,
        wheel_separation_multiplier: float = 1.0,
        publish_rate_hz: float = 50.0,
        pose_covariance_diagonal: Sequence[float] = DEFAULT_COVARIANCE_DIAGONAL,
        twist_covariance_diagonal: Sequence[float] = DEFAULT_COVARIANCE_DIAGONAL,
        signed_input: bool = False,
        publish_tf: bool = True,
        frame_id: str = ODOM_FRAME,
        child_frame_id: str = BASE_FRAME,
        speed_samples: str = "window",
        revolutions_per_sample: float = 1.0,
        sample_latency_s: float = 0.0,
        max_substep_s: float = 0.01,
        brake_stop_s: float = 0.62,
        brake_friction_rpm_s: float = 13.0,
        catchup_time_s: float = 0.1,
        catchup_max_fraction: float = 0.4,
        max_wheel_accel_m_s2: float = 4.0,
        sample_gap_s: float = 0.45,
        rest_rpm: float = 10.0,
        start_s: float = 0.5,
    ):
        if publish_rate_hz <= 0:
            raise ValueError(f"publish_rate_hz must be positive, got {publish_rate_hz}")
        if not (catchup_time_s > 0 and math.isfinite(catchup_time_s)):
            raise ValueError(f"catchup_time_s: {catchup_time_s} must be a finite number > 0")
        if not (catchup_max_fraction >= 0 and math.isfinite(catchup_max_fraction)):
            raise ValueError(
                f"catchup_max_fraction: {catchup_max_fraction} must be a finite number >= 0"
            )
        if not sample_gap_s >= 0:
            raise ValueError(
                f"sample_gap_s: {sample_gap_s} must be >= 0 (inf: samples held until the next)"
            )
        if not (rest_rpm >= 0 and math.isfinite(rest_rpm)):
            raise ValueError(f"rest_rpm: {rest_rpm} must be a finite number >= 0")
        if not (brake_friction_rpm_s >= 0 and math.isfinite(brake_friction_rpm_s)):
            raise ValueError(
                f"brake_friction_rpm_s: {brake_friction_rpm_s} must be a finite number >= 0"
            )
        if not max_wheel_accel_m_s2 > 0:
            raise ValueError(
                f"max_wheel_accel_m_s2: {max_wheel_accel_m_s2} must be > 0 (inf: no limit)"
            )
        self.bus, self.clock = bus, clock
        radius_m = wheel_radius_m * wheel_radius_multiplier
        self.left_radius_m = radius_m * left_radius_multiplier
        self.right_radius_m = radius_m * right_radius_multiplier
        self.separation_m = wheel_separation_m * wheel_separation_multiplier
        self.period_us = int(round(1e6 / publish_rate_hz))
        self.pose_covariance = covariance(pose_covariance_diagonal)
        self.twist_covariance = covariance(twist_covariance_diagonal)
        # shared by messages
        self.pose_covariance.flags.writeable = self.twist_covariance.flags.writeable = False
        self.signed_input, self.publish_tf = signed_input, publish_tf
        self.frame_id, self.child_frame_id = frame_id, child_frame_id
        self.max_substep_us = max(1, int(round(max_substep_s * 1e6)))
        # m/s per RPM
        self._rim = tuple(
            2.0 * math.pi / 60.0 * r for r in (self.left_radius_m, self.right_radius_m)
        )
        self.geometry = DriveGeometry(self.left_radius_m, self.right_radius_m, self.separation_m)
        """Wheel speeds (RPM) to the body twist the pose moves with."""
        self.published = PublishedPose(
            self.geometry,
            self.max_substep_us,
            tuple(max_wheel_accel_m_s2 * 1e-6 / k for k in self._rim),
            float(catchup_time_s),
            float(catchup_max_fraction),
        )
        gap_us = sample_gap_s * 1e6
        self.samples = WheelSpeedSamples(
            self.published,
            clock.now_us,
            signed_input=signed_input,
            speed_samples=speed_samples,
            revolutions_per_sample=revolutions_per_sample,
            sample_latency_us=int(round(sample_latency_s * 1e6)),
            brake_stop_us=max(0, int(round(brake_stop_s * 1e6))),
            brake_friction_rpm_s=brake_friction_rpm_s,
            start_us=max(0, int(round(start_s * 1e6))),
            sample_gap_us=gap_us if math.isinf(gap_us) else int(round(gap_us)),
            rest_rpm=rest_rpm,
        )
        self._seq = 0
        self.published.restart(clock.now_us, (0.0, 0.0, 0.0), (0.0, 0.0))
        bus.advertise(
            "odom", Odometry
        )  # declares the type; publish() hands messages to bus.publish
        self._subs = [
            bus.subscribe("wheel0_Vel", lambda m: self._on_speed(0, m)),
            bus.subscribe("wheel1_Vel", lambda m: self._on_speed(1, m)),
        ]
        if not signed_input:
            self._subs.append(bus.subscribe("wheel_Command", self._on_command))
        self._topics = ("odom", "tf") if publish_tf else ("odom",)
        self._timer = clock.schedule_every(
            clock.now_us, self.period_us, self._on_timer, publishes=self._topics
        )

    @property
    def x_m(self) -> float:
        """Published x in ``odom``, m (as of the last :meth:`update`)."""
        return self.published.pose[0]

    @property
    def y_m(self) -> float:
        """Published y in ``odom``, m (as of the last :meth:`update`)."""
        return self.published.pose[1]

    @property
    def yaw_rad(self) -> float:
        """Published yaw in ``odom``, rad, wrapped to [-pi, pi] (as of the last :meth:`update`)."""
        yaw = self.published.pose[2]
        return math.atan2(math.sin(yaw), math.cos(yaw))

    @property
    def speed_samples(self) -> str:
        """Meaning of a speed sample, ``"window"`` or ``"hold"`` (constructor)."""
        return self.samples.speed_samples

    @property
    def catchup_max_fraction(self) -> float:
        """Largest correction as a fraction of the wheels' speed and yaw rate (constructor)."""
        return self.published.catchup_max_fraction

    # -- inputs -----------------------------------------------------------------
    def _on_speed(self, wheel: int, msg: Float64) -> None:
        self.update()
        self.samples.sample(wheel, msg.data, self.clock.now_us)
        self.published.changed()

    def _on_command(self, msg: Float64MultiArray) -> None:
        self.update()
        data = msg.data
        self.samples.command(
            (int(data[0]), int(data[2])), (float(data[1]), float(data[3])), self.clock.now_us
        )
        self.published.changed()

    def set_wheel_speeds_rpm(self, left_rpm: float, right_rpm: float) -> None:
        """Signed wheel speeds from now on (forward positive), RPM."""
        self.update()
        now = self.clock.now_us
        for profile, rpm in zip(self.published.profiles, (left_rpm, right_rpm)):
            profile.cut(now)
            profile.step(now, rpm)
        self.published.changed()

    # -- state ------------------------------------------------------------------
    def body_twist(self) -> tuple[float, float, float]:
        """Body twist the published pose moves with now: ``vx_m_s, vy_m_s, w_rad_s`` (CCW +)."""
        self.update()
        return self.published.twist()

    def body_velocity(self) -> tuple[float, float]:
        """Forward speed (m/s) and yaw rate (rad/s, CCW +) the published pose moves with now."""
        vx, _vy, w = self.body_twist()
        return vx, w

    def update(self) -> None:
        """Integrate the published pose forward to ``clock.now_us``
        (:meth:`PublishedPose.advance`)."""
        self.published.advance(self.clock.now_us)

    def smoothed_pose(self) -> tuple[float, float, float]:
        """The smoothed (hindsight) pose now: ``x_m, y_m, yaw_rad`` in ``odom``, yaw wrapped."""
        self.update()
        x, y, yaw = self.published.smoothed.pose_at(self.published.t_us)
        return x, y, math.atan2(math.sin(yaw), math.cos(yaw))

    def reset(
        self, x_m: float = 0.0, y_m: float = 0.0, yaw_rad: float = 0.0, standing: bool = False
    ) -> None:
        """Set the pose in ``odom``: the speeds in force are kept, or, ``standing``, the node starts
        afresh (both wheels at rest, every earlier sample and command forgotten: a robot reset)."""
        self.update()
        now = self.clock.now_us
        rpm = (0.0, 0.0) if standing else self.published.smoothed.speeds_rpm(now)
        self.published.restart(now, (float(x_m), float(y_m), float(yaw_rad)), rpm)
        if standing:
            self.samples.reset(now)
        else:
            self.samples.restarted()

    # -- output -----------------------------------------------------------------
    def _on_timer(self) -> None:
        self.publish()

    def publish(self) -> Odometry:
        """Integrate to now, publish ``odom`` (and tf) and return the message
        (:func:`~amr_twin.controllers.odometry_message.odometry_message`; the bus's publish called
        directly: this runs at 50 Hz on the loop's cold caches)."""
        now = self.clock.now_us
        published = self.published
        # update(), once: body_twist() and the pose properties read its result
        published.advance(now)
        msg, transform = odometry_message(
            self._seq,
            now,
            published.pose,
            published.twist(),
            (self.frame_id, self.child_frame_id),
            (self.pose_covariance, self.twist_covariance),
            self.publish_tf,
        )
        self._seq += 1
        bus = self.bus
        bus.publish("odom", msg)
        if transform is not None:
            bus.send_transform(transform)
        return msg

    def shutdown(self) -> None:
        """Stop publishing and unsubscribe."""
        self._timer.cancel()
        for sub in self._subs:
            sub.unregister()
