"""What the VDA 5050 adapter needs of a vehicle (:class:`Vehicle`), and that of one twin with its
navigation stack (:class:`TwinVehicle`).

The adapter reads the vehicle's pose, velocity, battery, load and safety state and sends it goals;
it reaches no further, so that a world of N robots can hand it each of its robots the same way.
"""

from __future__ import annotations

import math
from typing import Protocol

STOP_ACTIONS = ("stop", "people_stop")
"""The collision monitor's actions that mean its protective field stopped the robot."""


class Vehicle(Protocol):
    """The narrow interface of one vehicle (SI units, REP-103 map frame)."""

    map_id: str

    def pose(self) -> tuple[float, float, float] | None:
        """The vehicle's own estimate (x_m, y_m, yaw_rad) in the map, None before it is
        localised."""

    def velocity(self) -> tuple[float, float]:
        """Forward speed m/s and yaw rate rad/s."""

    def battery(self) -> tuple[float, float]:
        """Terminal voltage V and state of charge (0-1)."""

    def payload_kg(self) -> float:
        """Mass of the load it carries, kg."""

    def estop_pressed(self) -> bool:
        """Whether the e-stop is pressed."""

    def field_violated(self) -> bool:
        """Whether a protective field stopped it since the last call."""

    def send_goal(self, x_m: float, y_m: float, yaw_rad: float | None):
        """Drive to a pose (preempting any goal); returns an object with ``status`` (``pending``,
        ``succeeded``, ``aborted``, ``canceled``, ``preempted``) and ``reason``."""

    def cancel(self) -> None:
        """Stop driving (ramp to a stop)."""


class TwinVehicle:
    """One twin driven by its navigator (:func:`amr_twin.navigation.stack.attach`), as a
    :class:`Vehicle`."""

    def __init__(self, twin, navigator, map_id: str, payload_kg: float = 0.0):
        self.twin, self.navigator, self.map_id = twin, navigator, map_id
        self._payload_kg = float(payload_kg)
        self._stops = self._stop_count()
        self._estops = [f for f in twin.options.faults if f.kind == "estop"]

    def _stop_count(self) -> int:
        actions = self.navigator.monitor.actions
        return sum(actions[k] for k in STOP_ACTIONS)

    def pose(self):
        source = self.navigator.pose_source
        return tuple(float(v) for v in source.pose()) if source.ready else None

    def velocity(self):
        v, w = self.navigator.pose_source.velocity
        return float(v), float(w)

    def battery(self):
        volt, _current, soc = self.twin.observables.battery()
        return float(volt), float(soc)

    def payload_kg(self) -> float:
        return self._payload_kg

    def estop_pressed(self) -> bool:
        t = self.twin.t_s
        return any(f.t_s <= t and (f.until_s is None or t < f.until_s) for f in self._estops)

    def field_violated(self) -> bool:
        n = self._stop_count()
        hit, self._stops = n > self._stops, n
        return hit

    def send_goal(self, x_m, y_m, yaw_rad):
        return self.navigator.send_goal(
            (float(x_m), float(y_m), None if yaw_rad is None else float(yaw_rad))
        )

    def cancel(self) -> None:
        self.navigator.cancel("canceled by the fleet manager")


def within(
    pose, x_m: float, y_m: float, theta_rad: float | None, xy_m: float, theta_tol_rad: float
) -> bool:
    """Whether ``pose`` lies within ``xy_m`` of (x_m, y_m) and, with a theta and ``theta_tol_rad`` >
    0, within that angle of it."""
    if pose is None or math.hypot(pose[0] - x_m, pose[1] - y_m) > xy_m:
        return False
    if theta_rad is None or theta_tol_rad <= 0:
        return True
    return abs(math.remainder(pose[2] - theta_rad, math.tau)) <= theta_tol_rad
