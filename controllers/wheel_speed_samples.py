"""Each wheel's speed estimate from the firmware's samples and the node's commands (no bus, no
clock).

A sample is a wheel's speed in RPM on the driver's SC output, which has no direction (§3.2.3): its
sign is the wheel's last non-zero ``wheel_Command`` motion code. Under a brake (motion 0) the speed
falls linearly to 0 over :meth:`WheelSpeedSamples.brake_us` (braked at 10 to 100 RPM, a hub wheel of
the twin covers the distance of such a ramp of 0.29 to 0.55 s; the model 0.31 to 0.54 s).

Reasons and measurements: docs/explanation/firmware.md#amr_twincontrollerswheel_speed_samples."""

from __future__ import annotations

import math

from amr_twin.estimation.published_pose import PublishedPose
from amr_twin.controllers.speed_bounds import silence_bound, start_ramp
from amr_twin.controllers.wheel_command import MAX_RPM

SPEED_SAMPLES = ("window", "hold")


class WheelSpeedSamples:
    """Both wheels' speed profiles, written from samples and commands as they arrive.

    Parameters
    ----------
    published : PublishedPose
        Holds the profiles (:attr:`PublishedPose.profiles`, replaced by its ``restart``).
    now_us : int
        Start instant, us.
    signed_input : bool
        Samples are signed RPM; commands are ignored.
    speed_samples : {"window", "hold"}
        Meaning of a sample (:mod:`amr_twin.controllers.odometry`).
    revolutions_per_sample : float
        Wheel revolutions one sample measures in ``"window"`` mode.
    sample_latency_us, brake_stop_us, start_us, sample_gap_us : int or inf
        Receipt delay of a sample; time a fast braked wheel takes to stop (twice the time constant
        of its shorted phases); time a wheel started from rest takes to reach its speed; longest
        wait of the firmware before it times the next revolution (``inf``: none known, a sample
        holds until the next). All us.
    brake_friction_rpm_s : float
        Constant deceleration of a braked wheel besides its shorted phases, RPM/s (0: every ramp
        lasts ``brake_stop_us``).
    rest_rpm : float
        Slowest speed a silent wheel is believed to turn at, RPM.
    """

    def __init__(
        self,
        published: PublishedPose,
        now_us: int,
        *,
        signed_input: bool,
        speed_samples: str,
        revolutions_per_sample: float,
        sample_latency_us: int,
        brake_stop_us: int,
        brake_friction_rpm_s: float,
        start_us: int,
        sample_gap_us: float,
        rest_rpm: float,
    ):
        if speed_samples not in SPEED_SAMPLES:
            raise ValueError(f"speed_samples: {speed_samples!r} is not one of {SPEED_SAMPLES}")
        self.published = published
        self.signed_input, self.speed_samples = signed_input, speed_samples
        self.revolutions_per_sample = float(revolutions_per_sample)
        self.sample_latency_us = sample_latency_us
        self.brake_stop_us, self.start_us = brake_stop_us, start_us
        self.sample_gap_us, self.rest_rpm = sample_gap_us, float(rest_rpm)
        self.brake_friction_rpm_s = float(brake_friction_rpm_s)
        self.reset(now_us)

    def reset(self, now_us: int) -> None:
        """Forget every sample and command: both wheels standing, never commanded, from
        ``now_us``."""
        self._direction = [1, 1]  # last non-zero motion: a braked wheel still turns that way
        # the end of each wheel's newest measurement window
        self._sample_us: list[int | None] = [None, None]
        self._command_rpm = [0.0, 0.0]  # each wheel's speed in the last wheel_Command, RPM
        self._brake_end_us = [0, 0]  # where each wheel's assumed brake ramp reaches 0
        self._motion_us = [now_us, now_us]  # each wheel's last change of motion code
        self._motion = [0, 0]

    def sample(self, wheel: int, value: float, now_us: int) -> None:
        """A speed sample of ``wheel`` (0 left, 1 right) received at ``now_us``: RPM, signed or
        not."""
        rpm = float(value) if self.signed_input else self._direction[wheel] * abs(float(value))
        profile = self.published.profiles[wheel]
        if profile.assumed_us is not None:  # its own sample replaces a stand-in
            profile.cut(profile.assumed_us)
            profile.assumed_us = None
        known_us = profile.known_us(now_us)
        if self.speed_samples == "hold":
            profile.cut(now_us)  # a measurement supersedes an assumed brake ramp
            profile.step(now_us, rpm)
            return
        t1 = now_us - self.sample_latency_us
        length_us = (self.revolutions_per_sample * 60e6 / abs(rpm)) if rpm else 1e15
        t0, held = t1 - length_us, rpm
        last_us = self._sample_us[wheel]
        done = abs(profile.revolutions(t0, known_us)) if rpm and t0 < known_us < t1 else 0.0
        if done > 0.0 if last_us is None else rpm and t0 < known_us < t1 and last_us <= t0:
            # the revolution began before the node's last knowledge of the wheel (a command, a
            # brake, the silence bound): keep its count (the SC output counts either way), place the
            # rest after it
            mean = min(
                max(self.revolutions_per_sample - done, 0.0) * 60e6 / (t1 - known_us), MAX_RPM
            )
            if profile.at(known_us, profile.segment(known_us)) == 0.0 and mean > 0.0:
                start_ramp(
                    profile,
                    known_us,
                    t1,
                    math.copysign(mean, rpm),
                    self.start_us,
                    self._command_rpm[wheel],
                )
                self._sample_us[wheel] = t1
                self._silence(wheel)
                self._mirror(wheel, now_us)
                return
            # slowing down: no faster after
            braked = self._motion[wheel] == 0 and not self.signed_input
            held = math.copysign(mean if braked else max(mean, abs(rpm)), rpm)
            rpm = math.copysign(mean, rpm)
        profile.cut(max(t0, known_us))
        if profile.last_rpm == 0.0:  # it stood before: it started with this window, not before
            profile.step(t0, 0.0)
        profile.window(t0, t1, rpm)
        if held != rpm:
            profile.step(t1, held)
        self._sample_us[wheel] = t1
        if (
            self._motion[wheel] == 0
            and not self.signed_input
            and self.brake_stop_us > 0
            and (last_us is None or last_us <= t0)
        ):
            # a revolution published under a brake: the wheel stops by the ramp's end, or now
            profile.point(max(self._brake_end_us[wheel], t1), 0.0)
        else:
            self._silence(wheel)
        self._mirror(wheel, now_us)

    def command(self, motions: tuple[int, int], rpms: tuple[float, float], now_us: int) -> None:
        """A ``wheel_Command`` at ``now_us``: both wheels' motion codes (1, -1, 0 brake) and speeds,
        RPM."""
        self._command_rpm = [abs(float(rpms[0])), abs(float(rpms[1]))]
        started: list[int] = []  # at rest, now commanded to move
        for wheel, motion in enumerate(motions):
            if motion == self._motion[wheel]:
                continue
            self._motion[wheel] = motion
            profile = self.published.profiles[wheel]
            profile.cut(now_us)
            profile.assumed_us = None  # a stand-in up to now is final
            if motion == 0:
                stop_us = self.brake_us(profile.last_rpm)
                profile.step(now_us, profile.last_rpm)
                profile.window(now_us + stop_us, now_us + stop_us, 0.0)
                self._brake_end_us[wheel] = now_us + stop_us
            elif profile.last_rpm == 0.0:
                self._direction[wheel] = 1 if motion > 0 else -1
                started.append(wheel)
            else:
                self._direction[wheel] = 1 if motion > 0 else -1
                profile.step(now_us, self._direction[wheel] * abs(profile.last_rpm))
                self._silence(wheel)
            self._motion_us[wheel] = now_us
        for profile in self.published.profiles:
            if profile.last_rpm == 0.0 and profile.last_us < now_us:
                profile.step(now_us, 0.0)  # at rest until this command: no motion before it
        self._start(started, now_us)

    def brake_us(self, rpm: float) -> int:
        """Length of the linear ramp to rest of a wheel braked at ``rpm``, us: as far as its shorted
        phases (a speed decaying with ``brake_stop_us / 2``) and ``brake_friction_rpm_s`` take
        it."""
        tau_s, speed, friction = 0.5e-6 * self.brake_stop_us, abs(rpm), self.brake_friction_rpm_s
        if speed == 0.0 or friction == 0.0 or tau_s == 0.0:
            return self.brake_stop_us
        # RPM s
        distance = tau_s * speed - friction * tau_s**2 * math.log1p(speed / (friction * tau_s))
        return int(round(2e6 * distance / speed))

    def restarted(self) -> None:
        """The profiles were restarted (a pose reset): bound the silence of the moving wheels
        again."""
        for wheel in (0, 1):
            if self._motion[wheel] != 0 or self.signed_input:
                self._silence(wheel)

    def _start(self, wheels: list[int], now_us: int) -> None:
        """Wheels at rest commanded to move at ``now_us``: a stand-in each until its next sample.

        Each ramps up over ``start_us`` to its commanded speed, held until one of them has turned
        what its open measurement window allows (a revolution since half the gap after its newest
        sample, counted on the profile, or one since now), then ramps down over ``start_us``: no
        sample by then means slower. The wheels keep the ratio of their commands (no yaw rate from
        two different bounds)."""
        wheels = [w for w in wheels if self._command_rpm[w] > 0.0]
        if self.speed_samples != "window" or self.signed_input or not wheels:
            return
        # at full speed
        full_us = min(self._allowed(w, now_us) * 60e6 / self._command_rpm[w] for w in wheels)
        if full_us <= 0.0:
            return
        ramp_us = self.start_us
        # of the commanded speed reached
        fraction = min(1.0, full_us / ramp_us) if ramp_us > 0 else 1.0
        hold_us = max(full_us - ramp_us, 0.0)
        for wheel in wheels:
            profile = self.published.profiles[wheel]
            peak = self._direction[wheel] * self._command_rpm[wheel]
            profile.step(now_us, 0.0)
            profile.point(now_us + ramp_us, fraction * peak)
            if math.isfinite(full_us):
                profile.point(now_us + ramp_us + hold_us, fraction * peak)
                profile.point(now_us + 2 * ramp_us + hold_us, 0.0)
            profile.assumed_us = now_us

    def _allowed(self, wheel: int, now_us: int) -> float:
        """Revolutions ``wheel`` can turn from ``now_us`` before its open window must be
        published."""
        last_us = self._sample_us[wheel]
        if not math.isfinite(self.sample_gap_us):
            return math.inf  # no silence bound: held until the sample
        if last_us is None:
            return self.revolutions_per_sample
        # the window opened within the gap
        opened_us = min(last_us + self.sample_gap_us // 2, now_us)
        done = abs(self.published.profiles[wheel].revolutions(opened_us, now_us))
        return max(self.revolutions_per_sample - done, 0.0)

    def _mirror(self, wheel: int, now_us: int) -> None:
        """The other wheel, not measured since this one's window, moves as this one, scaled.

        Not measured since its start: scaled by their commands (its first sample comes up to a
        revolution later). Measured before: scaled by the ratio of their speeds at its newest
        sample. The two estimates then change at the same instants (no yaw rate from one wheel
        measured against one held or assumed at rest); its own sample replaces this stand-in.
        """
        other = 1 - wheel
        src, dst = self.published.profiles[wheel], self.published.profiles[other]
        since_us = self._sample_us[other]
        if self.signed_input or self.speed_samples != "window" or 0 in self._motion:
            return
        if since_us is None or since_us < self._motion_us[other]:
            if self._command_rpm[wheel] <= 0.0:
                return
            ratio = self._command_rpm[other] / self._command_rpm[wheel]
            scale = ratio * self._direction[other] * self._direction[wheel]
            start_us = self._motion_us[other]
        else:
            if (
                since_us >= self._sample_us[wheel]
                or dst.assumed_us is None
                or since_us - max(self._motion_us) < self.start_us
            ):  # a ratio of speeds after the start
                return
            here, there = (
                src.at(since_us, src.segment(since_us)),
                dst.at(since_us, dst.segment(since_us)),
            )
            if here == 0.0 or there == 0.0:
                return
            scale, start_us = there / here, since_us
        t_cut = max(start_us, dst.t_us[0])
        # silent for longer than a revolution at rest_rpm takes: at rest from then on
        rev_us = self.revolutions_per_sample * 60e6
        rest_us = (
            start_us + self.sample_gap_us + rev_us / self.rest_rpm
            if self.rest_rpm > 0
            else math.inf
        )
        dst.cut(t_cut)
        dst.assumed_us = t_cut if now_us < rest_us else None
        for t_us, rpm in zip(src.t_us, src.rpm):
            if t_cut < t_us < rest_us:
                dst.point(t_us, scale * rpm)
        if math.isfinite(rest_us):
            dst.point(rest_us, dst.at(rest_us, dst.segment(rest_us)))
            dst.step(rest_us, 0.0)

    def _silence(self, wheel: int) -> None:
        """The silence bound (:func:`.speed_bounds.silence_bound`) after ``wheel``'s newest knot."""
        if self.speed_samples == "window":
            silence_bound(
                self.published.profiles[wheel],
                self._sample_us[wheel],
                self.sample_gap_us,
                self.revolutions_per_sample,
                self.rest_rpm,
            )
