"""Wheel odometry node: ``wheel0_Vel``/``wheel1_Vel`` to ``nav_msgs/Odometry`` on ``odom``.

The firmware publishes each wheel's speed in RPM as measured on the driver's SC
output, which has no direction (§3.2.3). The sign is taken from the last
``wheel_Command`` motion code of that wheel (1 forward, -1 backward); under a
brake (0) the wheel keeps its last direction and its speed falls linearly to 0
over ``brake_stop_s`` (a braked hub wheel stops in about 0.1 s from 30 RPM). With ``signed_input=True`` the wheel topics are read
as signed RPM and ``wheel_Command`` is ignored; :meth:`WheelOdometry.set_wheel_speeds_rpm`
feeds signed speeds directly.

What a speed sample means (``speed_samples``)
---------------------------------------------
``"window"`` (default)
    A sample of ``rpm`` received at ``t`` is the *mean* speed over its
    measurement window ``[t - revolutions_per_sample * 60 / rpm, t]``: the thesis
    firmware times exactly one revolution (90 SC changes) and publishes at its
    end. The window is clipped at the previous knowledge of that wheel (its
    previous sample, a brake, the node start), so a firmware that publishes
    faster than one revolution (the improved one, 10 Hz) gets the mean over the
    time since its previous sample. Between windows the speed is interpolated
    linearly; after the newest one it is held. The pose is re-integrated from
    the last instant known for both wheels whenever a sample arrives, so a
    sample corrects the past it describes (the published pose is a causal
    estimate, the stored one converges to the smoothed one).
``"hold"``
    Zero-order hold from the receipt of each sample (what a naive node does).
    With one sample per revolution it lags: the first sample of a start arrives
    about a revolution after the wheel started.

The estimate of each wheel is a list of knots (time, signed RPM), linear between
knots and held after the last. The pose is integrated exactly along arcs where
both speeds are constant and with arcs of at most ``max_substep_s`` at the mean
speeds where one varies (:mod:`amr_twin.controllers.dead_reckoning`). ``odom`` (frame ``odom``, child ``base_link``, REP-105)
and the ``odom -> base_link`` transform are published at ``publish_rate_hz``.

Known limits, inherited from the hardware: a wheel that stops without a brake
command keeps its last speed until a new sample; a motion sign change is applied
at command time while the wheel is still spinning the old way.
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

from .dead_reckoning import SpeedProfile, arc, integrate
from .wheel_command import WHEEL_RADIUS_M

WHEEL_SEPARATION_M = 0.48
"""``L`` of listing 4.2."""
DEFAULT_COVARIANCE_DIAGONAL = (1e-3, 1e-3, 1e6, 1e6, 1e6, 1e3)
"""(x, y, z, roll, pitch, yaw) variances, the ros_controllers diff_drive example values."""
SPEED_SAMPLES = ("window", "hold")


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
    speed_samples : {"window", "hold"}
        Meaning of a speed sample (module docstring).
    revolutions_per_sample : float
        Wheel revolutions one sample measures in ``"window"`` mode (thesis: 1).
    sample_latency_s : float
        Delay from the end of a measurement to its receipt, s (rosserial: ~1.4 ms).
    max_substep_s : float
        Longest arc while a speed varies, s.
    brake_stop_s : float
        Time a braked wheel takes to stop, s (the speed falls linearly).
    """

    def __init__(self, bus: Bus, clock: VirtualClock, wheel_radius_m: float = WHEEL_RADIUS_M,
                 wheel_separation_m: float = WHEEL_SEPARATION_M,
                 wheel_radius_multiplier: float = 1.0, left_radius_multiplier: float = 1.0,
                 right_radius_multiplier: float = 1.0, wheel_separation_multiplier: float = 1.0,
                 publish_rate_hz: float = 50.0,
                 pose_covariance_diagonal: Sequence[float] = DEFAULT_COVARIANCE_DIAGONAL,
                 twist_covariance_diagonal: Sequence[float] = DEFAULT_COVARIANCE_DIAGONAL,
                 signed_input: bool = False, publish_tf: bool = True,
                 frame_id: str = ODOM_FRAME, child_frame_id: str = BASE_FRAME,
                 speed_samples: str = "window", revolutions_per_sample: float = 1.0,
                 sample_latency_s: float = 0.0, max_substep_s: float = 0.01,
                 brake_stop_s: float = 0.1):
        if publish_rate_hz <= 0:
            raise ValueError(f"publish_rate_hz must be positive, got {publish_rate_hz}")
        if speed_samples not in SPEED_SAMPLES:
            raise ValueError(f"speed_samples: {speed_samples!r} is not one of {SPEED_SAMPLES}")
        self.bus, self.clock = bus, clock
        radius_m = wheel_radius_m * wheel_radius_multiplier
        self.left_radius_m = radius_m * left_radius_multiplier
        self.right_radius_m = radius_m * right_radius_multiplier
        self.separation_m = wheel_separation_m * wheel_separation_multiplier
        self.period_us = int(round(1e6 / publish_rate_hz))
        self.pose_covariance = _covariance(pose_covariance_diagonal)
        self.twist_covariance = _covariance(twist_covariance_diagonal)
        self.pose_covariance.flags.writeable = self.twist_covariance.flags.writeable = False  # shared by messages
        self.signed_input, self.publish_tf = signed_input, publish_tf
        self.frame_id, self.child_frame_id = frame_id, child_frame_id
        self.speed_samples = speed_samples
        self.revolutions_per_sample = float(revolutions_per_sample)
        self.sample_latency_us = int(round(sample_latency_s * 1e6))
        self.max_substep_us = max(1, int(round(max_substep_s * 1e6)))
        self.brake_stop_us = max(0, int(round(brake_stop_s * 1e6)))
        self._direction = [1, 1]  # last non-zero motion: a braked wheel still turns that way
        self.x_m = self.y_m = self.yaw_rad = 0.0
        self._motion = [0, 0]
        self._seq = 0
        self._restart(clock.now_us, (0.0, 0.0, 0.0), (0.0, 0.0))
        self._pub = bus.advertise("odom", Odometry)
        self._subs = [bus.subscribe("wheel0_Vel", lambda m: self._on_speed(0, m)),
                      bus.subscribe("wheel1_Vel", lambda m: self._on_speed(1, m))]
        if not signed_input:
            self._subs.append(bus.subscribe("wheel_Command", self._on_command))
        self._topics = ("odom", "tf") if publish_tf else ("odom",)
        self._timer = clock.schedule_in(self.period_us, self._on_timer, publishes=self._topics)

    def _restart(self, t_us: int, pose: tuple[float, float, float], rpm: Sequence[float]) -> None:
        self._profiles = [SpeedProfile(t_us, rpm[0]), SpeedProfile(t_us, rpm[1])]
        self._anchor = (t_us, *pose)  # final: no sample can change the pose before it
        self._cache = self._anchor  # pose at the newest knot of either wheel
        self._hold = None  # (v, w) when both speeds are held from the cache on
        self._dirty = False

    # -- inputs -----------------------------------------------------------------
    def _on_speed(self, wheel: int, msg: Float64) -> None:
        if self.signed_input:
            rpm = float(msg.data)
        else:
            rpm = self._direction[wheel] * abs(float(msg.data))
        now = self.clock.now_us
        profile = self._profiles[wheel]
        known_us = profile.known_us(now)
        if self.speed_samples == "hold":
            profile.cut(now)  # a measurement supersedes an assumed brake ramp
            profile.step(now, rpm)
        else:
            t1 = now - self.sample_latency_us
            length_us = (self.revolutions_per_sample * 60e6 / abs(rpm)) if rpm else 1e15
            profile.cut(max(t1 - length_us, known_us))
            profile.window(t1 - length_us, t1, rpm)
        self._dirty = True
        self.update()

    def _on_command(self, msg: Float64MultiArray) -> None:
        now = self.clock.now_us
        for wheel, motion in enumerate((int(msg.data[0]), int(msg.data[2]))):
            if motion == self._motion[wheel]:
                continue
            self._motion[wheel] = motion
            profile = self._profiles[wheel]
            profile.cut(now)
            if motion == 0:
                profile.step(now, profile.last_rpm)
                profile.window(now + self.brake_stop_us, now + self.brake_stop_us, 0.0)
            else:
                self._direction[wheel] = 1 if motion > 0 else -1
                profile.step(now, self._direction[wheel] * abs(profile.last_rpm))
            self._dirty = True
        for profile in self._profiles:
            if profile.last_rpm == 0.0 and profile.last_us < now:
                profile.step(now, 0.0)  # at rest until this command: no motion before it
                self._dirty = True
        self.update()

    def set_wheel_speeds_rpm(self, left_rpm: float, right_rpm: float) -> None:
        """Signed wheel speeds from now on (forward positive), RPM."""
        now = self.clock.now_us
        for profile, rpm in zip(self._profiles, (left_rpm, right_rpm)):
            profile.step(now, rpm)
        self._dirty = True
        self.update()

    # -- state ------------------------------------------------------------------
    def _body(self, left_rpm: float, right_rpm: float) -> tuple[float, float]:
        v_left = left_rpm * 2.0 * math.pi / 60.0 * self.left_radius_m
        v_right = right_rpm * 2.0 * math.pi / 60.0 * self.right_radius_m
        return 0.5 * (v_left + v_right), (v_right - v_left) / self.separation_m

    def body_velocity(self) -> tuple[float, float]:
        """Current forward speed (m/s) and yaw rate (rad/s, CCW +) of ``base_link``."""
        now = self.clock.now_us
        if self._hold is not None and not self._dirty and now >= self._cache[0]:
            return self._hold
        return self._body(*(p.at(now, p.segment(now)) for p in self._profiles))

    def update(self) -> None:
        """Bring the pose up to ``clock.now_us`` (re-integrating after new samples)."""
        now = self.clock.now_us
        if self._dirty:
            # final up to the last knot at or before now of each wheel: later samples are
            # clipped there (knots after now are assumptions, e.g. a brake ramp)
            horizon = min(p.known_us(now) for p in self._profiles)
            if horizon > self._anchor[0]:
                self._anchor = integrate(self._profiles, self._anchor, horizon, self.max_substep_us,
                                         self._body)
                for p in self._profiles:
                    p.trim(horizon)
            newest = min(max(p.last_us for p in self._profiles), now)
            self._cache = integrate(self._profiles, self._anchor, max(newest, self._anchor[0]),
                                    self.max_substep_us, self._body)
            self._dirty = False
            self._hold = None
            if all(p.last_us <= self._cache[0] for p in self._profiles):  # speeds held after the cache
                self._hold = self._body(self._profiles[0].last_rpm, self._profiles[1].last_rpm)
        cache, hold = self._cache, self._hold
        if now <= cache[0]:
            pose = cache[1:]
        elif hold is not None:  # one arc at the held speeds: what integrate computes, cheaper
            pose = arc(cache[1:], hold[0], hold[1], float(now - cache[0]) * 1e-6)
        else:
            _, *pose = integrate(self._profiles, cache, now, self.max_substep_us, self._body)
        self.x_m, self.y_m = pose[0], pose[1]
        self.yaw_rad = math.atan2(math.sin(pose[2]), math.cos(pose[2]))

    def reset(self, x_m: float = 0.0, y_m: float = 0.0, yaw_rad: float = 0.0) -> None:
        """Set the pose in ``odom`` (the speeds in force are kept)."""
        rpm = [p.last_rpm for p in self._profiles]
        self._restart(self.clock.now_us, (float(x_m), float(y_m), float(yaw_rad)), rpm)
        self.update()

    # -- output -----------------------------------------------------------------
    def _on_timer(self) -> None:
        self._timer = self.clock.schedule_in(self.period_us, self._on_timer, publishes=self._topics)
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
                                    self.pose_covariance),
            twist=TwistWithCovariance(Twist(Vector3(v_m_s, 0.0, 0.0), Vector3(0.0, 0.0, w_rad_s)),
                                      self.twist_covariance))
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
