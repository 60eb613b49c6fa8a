"""One UMBmark square driven by the twin on its own wheel odometry (Borenstein and Feng, 1996).

The robot starts at rest at the origin of ``odom``, drives ``side_m`` straight, stops, turns
90 degrees in place (left for counter-clockwise, right for clockwise) and so on four times, each
leg and each turn ended when the wheel odometry node (:class:`~amr_twin.controllers.odometry.WheelOdometry`,
calibrated or not) says so, as the UMBmark protocol drives a real robot. The commands go through
the ``wheel_Command`` client as a user's would (``linear``, ``angular`` about an ICC of 0,
``stop``); the twin's clock advances in 10 ms steps between the checks. What is returned is the
return position as the odometry believes it and as it is (the physics' pose in the start's frame):
their difference is the run's return position error.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

STEP_S = 0.01
"""Time between two looks at the odometry, s."""
SETTLE_S = 1.0
"""Standing still after each stop, s (the wheels and the odometry's brake ramp come to rest)."""
STOP_S = 0.25
"""A leg or a turn is stopped this long before the odometry reaches its end (what the wheels roll
while the firmware brakes; the odometry counts it)."""
MAX_LEG_S = 60.0
"""A leg or a turn that has not ended by then is a failure (bounded runs)."""


@dataclass(frozen=True)
class SquareRun:
    """One square: the return position by odometry and in truth (the start's frame, m) and their
    difference ``error = true - odometry`` (Borenstein's epsilon = x_abs - x_calc)."""

    direction: str
    run: int
    odom_x_m: float
    odom_y_m: float
    true_x_m: float
    true_y_m: float
    true_yaw_deg: float
    sim_s: float

    @property
    def error_x_m(self) -> float:
        return self.true_x_m - self.odom_x_m

    @property
    def error_y_m(self) -> float:
        return self.true_y_m - self.odom_y_m


def _true_pose(twin, start) -> tuple[float, float, float]:
    p = twin.physics.pose()
    x0, y0, yaw0 = start
    dx, dy = p.x_m - x0, p.y_m - y0
    c, s = math.cos(yaw0), math.sin(yaw0)
    return c * dx + s * dy, -s * dx + c * dy, p.yaw_rad - yaw0


def _until(twin, done, what: str) -> None:
    t_end = twin.t_s + MAX_LEG_S
    while not done():
        if twin.t_s > t_end:
            raise RuntimeError(f"UMBmark square: {what} did not end within {MAX_LEG_S:g} s")
        twin.advance(STEP_S)


def drive_square(twin, direction: str, side_m: float, speed_m_s: float, turn_deg_s: float,
                 run: int = 0) -> SquareRun:
    """Drive one square (``direction`` ``"cw"`` or ``"ccw"``) with ``twin`` from where it stands."""
    if direction not in ("cw", "ccw"):
        raise ValueError(f"direction: {direction!r} must be cw or ccw")
    odo, client = twin.odometry, twin.client
    p = twin.physics.pose()
    start = (p.x_m, p.y_m, p.yaw_rad)
    sign = 1.0 if direction == "ccw" else -1.0
    for leg in range(4):
        x0, y0 = odo.x_m, odo.y_m
        gone = lambda: math.hypot(odo.x_m - x0, odo.y_m - y0)  # noqa: E731
        client.linear(speed_m_s)
        _until(twin, lambda: gone() >= side_m - 0.5 * speed_m_s * STOP_S, "a leg")
        client.stop()
        twin.advance(SETTLE_S)
        yaw0 = odo.yaw_rad
        turned = lambda: sign * math.remainder(odo.yaw_rad - yaw0, 2 * math.pi)  # noqa: E731
        client.angular(sign * turn_deg_s, 0.0)
        _until(twin, lambda: turned() >= math.radians(90.0 - 0.5 * turn_deg_s * STOP_S), "a turn")
        client.stop()
        twin.advance(SETTLE_S)
    tx, ty, tyaw = _true_pose(twin, start)
    return SquareRun(direction, run, odo.x_m, odo.y_m, tx, ty, math.degrees(math.remainder(tyaw, 2 * math.pi)),
                     twin.t_s)
