"""What the VDA 5050 adapter needs of a vehicle (:class:`Vehicle`), and that of one twin with its
navigation stack (:class:`TwinVehicle`).

The adapter reads the vehicle's pose, velocity, battery and safety state, sends it goals, and puts a
load on it or a charger to it; it reaches no further, so that a world of N robots can hand it each
of its robots the same way.
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

    def set_payload_kg(self, mass_kg: float) -> None:
        """Carry a load of ``mass_kg`` kg from now on (0: none)."""

    def set_charging(self, on: bool) -> None:
        """Connect its charger (at a charging station), or disconnect it."""

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
    """One robot of a world (:class:`~amr_twin.assembly.robot.Robot`) driven by its navigator
    (:func:`amr_twin.navigation.stack.attach`), as a :class:`Vehicle`."""

    def __init__(self, robot, navigator, map_id: str, charge_current_a: float):
        self.robot, self.navigator, self.map_id = robot, navigator, map_id
        self.charge_current_a = charge_current_a
        self._stops = self._stop_count()
        self._estops = [f for f in robot.spec.faults if f.kind == "estop"]

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
        volt, _current, soc = self.robot.observables.battery()
        return float(volt), float(soc)

    def set_payload_kg(self, mass_kg: float) -> None:
        self.robot.set_payload_kg(mass_kg)

    def set_charging(self, on: bool) -> None:
        self.robot.set_charger_a(self.charge_current_a if on else 0.0)

    def estop_pressed(self) -> bool:
        t = self.robot.t_s
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
