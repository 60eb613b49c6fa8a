"""High-level wheel commands: ``wheel_Command_Service`` and ``wheel_Command_Client`` (§3.2.2,
§4.2.1).

The client converts user-format data (m/s, deg/s, ICC in m) to service-format
data (motion code and RPM per wheel) as listings 4.4-4.6 do, checks each speed
against ``[min_rpm, max_rpm]`` and calls the service; the service publishes
``wheel_Command`` = ``std_msgs/Float64MultiArray [motionL, speedL, motionR, speedR]``.

Return codes (§4.2.1): 0 ok, 1 value error, -1 the service call failed.

Reasons and measurements: docs/explanation/firmware.md#amr_twincontrollerswheel_command."""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from amr_twin.ros.bus import Bus, ServiceCallError
from amr_twin.ros.messages import Float64MultiArray

LOG = logging.getLogger(__name__)

MAX_VEL_RPM = 1054.0
MIN_RPM = 0.0
MAX_RPM = MAX_VEL_RPM
FORWARD, BACKWARD, STOP = 1, -1, 0
OK, VALUE_ERROR, CALL_FAILED = 0, 1, -1
SERVICE_NAME = "wheel_Command_Service"
TOPIC = "wheel_Command"


@dataclass(slots=True)
class WheelCommandRequest:
    """Request of ``amr_idea_control/RequestPacket`` (motion codes, speeds in RPM)."""

    _type: ClassVar[str] = "amr_idea_control/RequestPacketRequest"
    motionL: int = 0
    speedL: float = 0.0
    motionR: int = 0
    speedR: float = 0.0


@dataclass(slots=True)
class WheelCommandResponse:
    """Response of ``amr_idea_control/RequestPacket`` (not printed in the thesis: empty)."""

    _type: ClassVar[str] = "amr_idea_control/RequestPacketResponse"


class WheelCommandService:
    """Service server ``wheel_Command_Service`` publishing ``wheel_Command`` (listing 4.3)."""

    def __init__(
        self, bus: Bus, service_name: str = SERVICE_NAME, topic: str = TOPIC, queue_size: int = 100
    ):
        self.bus = bus
        self.service_name = service_name
        self._pub = bus.advertise(topic, Float64MultiArray, queue_size=queue_size)
        bus.advertise_service(service_name, self.request_command)

    def send_command(self, motionL: int, speedL: float, motionR: int, speedR: float) -> None:
        """Publish ``[motionL, speedL, motionR, speedR]`` on ``wheel_Command``."""
        self._pub.publish(
            Float64MultiArray(
                data=[float(int(motionL)), float(speedL), float(int(motionR)), float(speedR)]
            )
        )

    def request_command(self, req: WheelCommandRequest) -> WheelCommandResponse:
        """Service handler: forward the request to :meth:`send_command`."""
        self.send_command(req.motionL, req.speedL, req.motionR, req.speedR)
        return WheelCommandResponse()

    def shutdown(self) -> None:
        """Withdraw the service."""
        self.bus.unadvertise_service(self.service_name)


class WheelCommandClient:
    """User-format commands converted and sent to ``wheel_Command_Service``.

    Parameters
    ----------
    bus : Bus
        Bus carrying the service.
    wheel_radius_m : float
        Drive wheel radius, m (``wheel.radius_m``; thesis: WHEEL_DIAM 0.25 m).
    half_separation_m : float
        ``R`` of listing 4.2, wheel centre to the robot mid point, m (half ``wheel.separation_m``).
    min_rpm, max_rpm : float
        Accepted range of each wheel's |speed|, RPM.
    listing_motion_codes : bool
        Reproduce listing 4.5's FORWARD/FORWARD when ``|icc| >= R``.
    float32_request : bool
        Round speeds to float32 as the request fields are.
    """

    def __init__(
        self,
        bus: Bus,
        *,
        wheel_radius_m: float,
        half_separation_m: float,
        min_rpm: float = MIN_RPM,
        max_rpm: float = MAX_RPM,
        listing_motion_codes: bool = False,
        float32_request: bool = True,
        service_name: str = SERVICE_NAME,
    ):
        self.bus = bus
        self.wheel_radius_m = float(wheel_radius_m)
        self.half_separation_m = float(half_separation_m)
        self.min_rpm, self.max_rpm = float(min_rpm), float(max_rpm)
        self.listing_motion_codes = listing_motion_codes
        self.float32_request = float32_request
        self.service_name = service_name
        self.last_error: str | None = None
        self.last_request: WheelCommandRequest | None = None

    # -- conversions (wheel.cpp) ------------------------------------------------
    def compute_rpm(self, speed_m_s: float) -> float:
        """Wheel RPM of a rim speed: ``v * 60 / (pi * diameter)``."""
        return speed_m_s * 60.0 / (math.pi * 2.0 * self.wheel_radius_m)

    def check_speed(self, rpm: float) -> bool:
        """True if ``rpm`` is finite and ``min_rpm <= |rpm| <= max_rpm``."""
        return math.isfinite(rpm) and self.min_rpm <= abs(rpm) <= self.max_rpm

    checkSpeed = check_speed

    # -- commands ---------------------------------------------------------------
    def linear(self, speed_m_s: float) -> int:
        """Both wheels at ``speed_m_s`` (negative: backward, motion -1). Listing 4.4."""
        bad = self._not_finite(speed_m_s=speed_m_s)
        rpm = math.nan if bad else self.compute_rpm(speed_m_s)
        if bad or not self.check_speed(rpm):
            return self._value_error("ERROR: linear velocity not valid", bad or self._range(rpm))
        motion = FORWARD if rpm >= 0 else BACKWARD
        return self._call(motion, abs(rpm), motion, abs(rpm), "ERROR while linear motion")

    def angular(self, speed_deg_s: float, icc_m: float) -> int:
        """Rotation at ``speed_deg_s`` (CCW +) about an ICC ``icc_m`` to the left. Listing 4.5."""
        bad = self._not_finite(speed_deg_s=speed_deg_s, icc_m=icc_m)
        if bad:
            return self._value_error("ERROR: angular velocity not valid", bad)
        omega_rad_s = math.radians(speed_deg_s)
        rpm_l = self.compute_rpm(omega_rad_s * (icc_m - self.half_separation_m))
        rpm_r = self.compute_rpm(omega_rad_s * (icc_m + self.half_separation_m))
        if self.listing_motion_codes and abs(icc_m) >= self.half_separation_m:
            motion_l = motion_r = FORWARD
        else:
            motion_l = FORWARD if rpm_l >= 0 else BACKWARD
            motion_r = FORWARD if rpm_r >= 0 else BACKWARD
        for rpm in (rpm_l, rpm_r):
            if not self.check_speed(rpm):
                return self._value_error("ERROR: angular velocity not valid", self._range(rpm))
        return self._call(motion_l, abs(rpm_l), motion_r, abs(rpm_r), "ERROR while angular motion")

    def stop(self) -> int:
        """Brake both wheels (motion 0, speed 0; fig. 3.7). Listing 4.6."""
        return self._call(STOP, 0.0, STOP, 0.0, "ERROR while stop motion")

    def motor(self, wheel: str | int, direction: str | int, speed_m_s: float) -> int:
        """One wheel at ``speed_m_s`` >= 0; the other free-spins (motion 1, speed 0; fig. 3.6).

        ``wheel`` is "left"/0 or "right"/1, ``direction`` "forward"/1 or "backward"/-1.
        """
        side = {"left": 0, 0: 0, "right": 1, 1: 1}.get(wheel)
        motion = {"forward": FORWARD, 1: FORWARD, "backward": BACKWARD, -1: BACKWARD}.get(direction)
        text = "ERROR: motor velocity not valid"
        if side is None or motion is None:
            return self._value_error(text, f"wheel={wheel!r}, direction={direction!r}")
        bad = self._not_finite(speed_m_s=speed_m_s)
        if bad or speed_m_s < 0:
            return self._value_error(text, bad or f"speed_m_s={speed_m_s} < 0 (use direction)")
        rpm = self.compute_rpm(speed_m_s)
        if not self.check_speed(rpm):
            return self._value_error(text, self._range(rpm))
        cmd = (motion, rpm, FORWARD, 0.0) if side == 0 else (FORWARD, 0.0, motion, rpm)
        return self._call(*cmd, "ERROR while motor motion")

    def wheels(self, left_m_s: float, right_m_s: float, brake_zero: bool = True) -> int:
        """Signed rim speed per wheel (used by the diff-drive node).

        A wheel at exactly 0 is braked (motion 0) with ``brake_zero``, else free-spins.
        """
        bad = self._not_finite(left_m_s=left_m_s, right_m_s=right_m_s)
        if bad:
            return self._value_error("ERROR: wheel velocity not valid", bad)
        codes = []
        for rpm in (self.compute_rpm(left_m_s), self.compute_rpm(right_m_s)):
            if not self.check_speed(rpm):
                return self._value_error("ERROR: wheel velocity not valid", self._range(rpm))
            motion = STOP if rpm == 0 and brake_zero else (FORWARD if rpm >= 0 else BACKWARD)
            codes += [motion, abs(rpm)]
        return self._call(*codes, "ERROR while wheel motion")

    # -- helpers ----------------------------------------------------------------
    @staticmethod
    def _not_finite(**values: float) -> str:
        for name, value in values.items():
            try:
                finite = math.isfinite(value)
            except TypeError:
                finite = False
            if not finite:
                return f"{name}={value!r} is not a finite number"
        return ""

    def _range(self, rpm: float) -> str:
        return f"|{rpm:.4f}| RPM outside [{self.min_rpm:g}, {self.max_rpm:g}]"

    def _value_error(self, text: str, detail: str) -> int:
        self.last_error = f"{text}: {detail}"
        LOG.error(self.last_error)
        return VALUE_ERROR

    def _call(
        self, motion_l: int, speed_l: float, motion_r: int, speed_r: float, failure_text: str
    ) -> int:
        if self.float32_request:
            speed_l, speed_r = float(np.float32(speed_l)), float(np.float32(speed_r))
        req = WheelCommandRequest(motion_l, speed_l, motion_r, speed_r)
        self.last_request = req
        try:
            self.bus.call_service(self.service_name, req)
        except ServiceCallError as exc:
            self.last_error = f"{failure_text}: {exc}"
            LOG.error(self.last_error)
            return CALL_FAILED
        self.last_error = None
        return OK


wheel_Command_Service = WheelCommandService
"""The thesis' node name."""
wheel_Command_Client = WheelCommandClient
"""The thesis' node name."""
