"""Diff-drive node: ``geometry_msgs/Twist`` on ``cmd_vel`` to wheel commands.

Not in the thesis (its client is a terminal menu); it lets planners and teleop
drive the twin the ROS way. For a twist ``(v, omega)`` (``linear.x`` m/s,
``angular.z`` rad/s, REP-103) the rim speeds are ``v_left = v - omega * R`` and
``v_right = v + omega * R`` with ``R`` the client's half separation; they go to
:meth:`WheelCommandClient.wheels` (per-wheel RPM and motion codes, a wheel at
exactly 0 is braked). A twist of all zeros is sent as the thesis' ``stop()``.

Saturation: if a wheel would exceed the client's ``max_rpm``, both wheels are
scaled by the same factor (the path curvature is kept) when ``saturate`` is set;
otherwise the client refuses the command (code 1) and the last command stays.

Timeout: every accepted ``cmd_vel`` re-arms a clock event ``cmd_timeout_s``
later; if it fires, the node calls ``stop()`` once. Identical consecutive
commands are not re-sent (the firmware's ramp would restart on each one) unless
``resend_identical`` is set.
"""

from __future__ import annotations

import logging
import math

from amr_twin.ros.bus import Bus
from amr_twin.base.clock import EventHandle, VirtualClock
from amr_twin.ros.geometry_messages import Twist

from amr_twin.controllers.wheel_command import OK, WheelCommandClient

LOG = logging.getLogger(__name__)


class DiffDriveNode:
    """Subscribe ``cmd_vel`` and command the wheels through a :class:`WheelCommandClient`.

    Parameters
    ----------
    bus : Bus
        Bus carrying ``cmd_vel`` and the wheel command service.
    clock : VirtualClock
        Shared clock used for the command timeout.
    client : WheelCommandClient
        Client used to send commands (the twin's: ``twin.client``, with the configured geometry).
    cmd_timeout_s : float
        Stop the wheels this long after the last ``cmd_vel``, seconds (<= 0: never).
    saturate : bool
        Scale both wheels down to ``client.max_rpm`` instead of refusing.
    resend_identical : bool
        Send a command even when it equals the previous one.
    topic : str
        Input topic name.
    """

    def __init__(
        self,
        bus: Bus,
        clock: VirtualClock,
        client: WheelCommandClient,
        cmd_timeout_s: float = 0.5,
        saturate: bool = True,
        resend_identical: bool = False,
        topic: str = "cmd_vel",
    ):
        self.bus, self.clock = bus, clock
        self.client = client
        self.cmd_timeout_us = int(round(cmd_timeout_s * 1e6))
        self.saturate = saturate
        self.resend_identical = resend_identical
        self.last_code: int | None = None
        """Return code of the last command sent (0, 1 or -1)."""
        self.timed_out = False
        self._last_sent: tuple[float, float] | None = None
        self._timeout: EventHandle | None = None
        bus.advertise(topic, Twist)
        self._sub = bus.subscribe(topic, self.on_cmd_vel, queue_size=1)

    def wheel_speeds_m_s(self, linear_m_s: float, angular_rad_s: float) -> tuple[float, float]:
        """Left and right rim speeds, m/s, saturated if :attr:`saturate` is set."""
        half_sep_m = self.client.half_separation_m
        left_m_s = linear_m_s - angular_rad_s * half_sep_m
        right_m_s = linear_m_s + angular_rad_s * half_sep_m
        if self.saturate:
            limit_m_s = self.client.max_rpm * math.pi * 2.0 * self.client.wheel_radius_m / 60.0
            peak_m_s = max(abs(left_m_s), abs(right_m_s))
            if peak_m_s > limit_m_s:
                scale = limit_m_s / peak_m_s
                left_m_s, right_m_s = left_m_s * scale, right_m_s * scale
        return left_m_s, right_m_s

    def on_cmd_vel(self, msg: Twist) -> None:
        """Convert a twist to wheel commands and re-arm the timeout."""
        linear_m_s, angular_rad_s = msg.linear.x, msg.angular.z
        if not (math.isfinite(linear_m_s) and math.isfinite(angular_rad_s)):
            LOG.error("cmd_vel ignored: non-finite twist (%r, %r)", linear_m_s, angular_rad_s)
            return
        speeds = self.wheel_speeds_m_s(linear_m_s, angular_rad_s)
        if speeds != self._last_sent or self.resend_identical or self.timed_out:
            if speeds == (0.0, 0.0):
                self.last_code = self.client.stop()
            else:
                self.last_code = self.client.wheels(*speeds)
            if self.last_code == OK:
                self._last_sent = speeds
        self.timed_out = False
        self._arm_timeout()

    def _arm_timeout(self) -> None:
        if self._timeout is not None:
            self._timeout.cancel()
        if self.cmd_timeout_us > 0:
            self._timeout = self.clock.schedule_in(self.cmd_timeout_us, self._on_timeout)

    def _on_timeout(self) -> None:
        self._timeout = None
        self.timed_out = True
        self.last_code = self.client.stop()
        self._last_sent = (0.0, 0.0) if self.last_code == OK else None
        LOG.info("cmd_vel timeout at t=%.3f s: wheels stopped", self.clock.now_s)

    def shutdown(self) -> None:
        """Unsubscribe and cancel the pending timeout."""
        self._sub.unregister()
        if self._timeout is not None:
            self._timeout.cancel()
            self._timeout = None
