"""One UMBmark square driven by the twin on its own wheel odometry (Borenstein and Feng, 1996).

Reasons and measurements: docs/explanation/umbmark.md#amr_twinexperimentsumbmarksquare."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from amr_twin.estimation.dead_reckoning import arc

DIRECTIONS = ("cw", "ccw")
MAX_MOTION_S = 60.0
"""A leg or a turn that has not ended by then is a failure (bounded runs)."""
POLL_S = 0.02
"""The twin advances this long between looks at whether the driver is done, s."""


@dataclass(frozen=True)
class Profile:
    """How the square is driven (module notes). Speeds and accelerations are the wheels' at the
    rim (a turn's rate is its wheels' speed over half the wheelbase)."""

    side_m: float = 4.0
    speed_m_s: float = 0.4
    turn_deg_s: float = 45.0
    accel_m_s2: float = 0.5
    stop_speed_m_s: float = 0.08
    crawl_s: float = 0.3
    brake_lead_s: float = 0.15
    rest_s: float = 1.0
    lookahead_m: float = 1.0
    max_curvature_1_m: float = 0.5


@dataclass(frozen=True)
class SquareRun:
    """One square: return poses (the start's frame, m, deg) by the odometry node, by the wheels'
    true angles with the odometry's geometry and with the true one, and in truth."""

    direction: str
    run: int
    seed: int
    node_xy_m: tuple[float, float]
    wheels_xy_m: tuple[float, float]
    wheels_true_geometry_xy_m: tuple[float, float]
    true_xy_m: tuple[float, float]
    node_yaw_deg: float
    true_yaw_deg: float
    sim_s: float

    @property
    def error_m(self) -> tuple[float, float]:
        """UMBmark's return error ``true - node`` (Borenstein's epsilon = x_abs - x_calc), m."""
        return (self.true_xy_m[0] - self.node_xy_m[0], self.true_xy_m[1] - self.node_xy_m[1])

    @property
    def wheels_error_m(self) -> tuple[float, float]:
        """``true - wheels(the odometry's geometry)``: geometry and slip, m."""
        return (self.true_xy_m[0] - self.wheels_xy_m[0], self.true_xy_m[1] - self.wheels_xy_m[1])

    @property
    def slip_error_m(self) -> tuple[float, float]:
        """``true - wheels(true geometry)``: what the tyres do on the floor, m."""
        return (
            self.true_xy_m[0] - self.wheels_true_geometry_xy_m[0],
            self.true_xy_m[1] - self.wheels_true_geometry_xy_m[1],
        )


class SquareDriver:
    """The square's driver: a node that acts on each ``wheel1_Vel`` sample (module notes).

    It drives the square by its odometry, as a UMBmark robot is programmed to: the corners are
    ``(side, 0)``, ``(side, ±side)``, ``(0, ±side)`` and the start in the odometry's frame, each leg
    steers onto the line from the previous corner to the next (pure pursuit, ``lookahead_m``) and
    ends abreast of the corner, each turn ends at the next leg's heading (not 90 degrees from where
    the last one ended), so a turn's end error is taken out by the next leg instead of bending the
    rest of the square."""

    def __init__(self, twin, profile: Profile):
        self.twin, self.profile = twin, profile
        self.odometry, self.client = twin.nodes["odometry"], twin.client
        self.half_separation_m = 0.5 * twin.cfg.wheel.separation_m
        fw = twin.firmware.p
        self.period_s = fw.pi_period_us * fw.publish_every_ticks * 1e-6
        self._task: dict | None = None
        self._sub = twin.bus.subscribe("wheel1_Vel", self._on_sample)

    def _remaining_m(self, task: dict) -> float:
        """What is left of the motion by the odometry, m of rim (a leg: along its line to the
        corner)."""
        odo = self.odometry
        if task["turn"]:
            return (
                task["sign"]
                * math.remainder(task["yaw"] - odo.yaw_rad, 2 * math.pi)
                * self.half_separation_m
            )
        ux, uy = math.cos(task["yaw"]), math.sin(task["yaw"])
        return (task["x"] - odo.x_m) * ux + (task["y"] - odo.y_m) * uy

    def _curvature(self, task: dict, remaining_m: float) -> float:
        """Pure pursuit onto the leg's line: the curvature (1/m, + left) of the arc through the
        point ``lookahead_m`` further along the line than the robot, by the odometry, bounded."""
        odo, p = self.odometry, self.profile
        ux, uy = math.cos(task["yaw"]), math.sin(task["yaw"])
        gx = task["x"] - (remaining_m - p.lookahead_m) * ux - odo.x_m
        gy = task["y"] - (remaining_m - p.lookahead_m) * uy - odo.y_m
        c, s = math.cos(odo.yaw_rad), math.sin(odo.yaw_rad)
        lateral, distance2 = -s * gx + c * gy, gx * gx + gy * gy
        kappa = 2.0 * lateral / distance2
        return max(-p.max_curvature_1_m, min(p.max_curvature_1_m, kappa))

    def _on_sample(self, _msg) -> None:
        """The odometry has just integrated a sample: brake if this is the sample nearest the end,
        else the next speed of the trapezoid (sent now, so starts and stops fall on samples)."""
        task = self._task
        if task is None:
            return
        p, period = self.profile, self.period_s
        remaining = self._remaining_m(task)
        command = task["command"]
        if command > 0.0 and remaining <= command * (p.brake_lead_s + 0.5 * period):
            self.client.stop()
            self._task = None
            return
        approach = remaining - p.stop_speed_m_s * (
            p.crawl_s + p.brake_lead_s
        )  # the crawl, then the brake
        reach = math.sqrt(p.stop_speed_m_s**2 + 2.0 * p.accel_m_s2 * max(approach, 0.0))
        command = max(min(task["cruise"], command + p.accel_m_s2 * period, reach), p.stop_speed_m_s)
        task["command"] = command
        if task["turn"]:
            self.client.angular(task["sign"] * math.degrees(command / self.half_separation_m), 0.0)
        elif p.lookahead_m > 0.0:
            # the wheels' difference moves by at most accel a sample (the ramp's own limit)
            step = p.accel_m_s2 * period
            delta = command * self._curvature(task, remaining) * self.half_separation_m
            delta = task["delta"] = max(task["delta"] - step, min(task["delta"] + step, delta))
            self.client.wheels(command - delta, command + delta)
        else:
            self.client.linear(command)

    def _motion(
        self, turn: bool, x_m: float, y_m: float, yaw_rad: float, sign: float = 1.0
    ) -> None:
        """One leg to the corner ``(x_m, y_m)`` along heading ``yaw_rad``, or a turn in place to
        ``yaw_rad`` (``sign`` +1 left), by the odometry; then the rest."""
        p, twin = self.profile, self.twin
        cruise = math.radians(p.turn_deg_s) * self.half_separation_m if turn else p.speed_m_s
        self._task = dict(
            turn=turn, x=x_m, y=y_m, yaw=yaw_rad, sign=sign, cruise=cruise, command=0.0, delta=0.0
        )
        t_end = twin.t_s + MAX_MOTION_S
        while self._task is not None:
            if twin.t_s > t_end:
                self._task = None
                self.client.stop()
                raise RuntimeError(
                    f"UMBmark square: a {'turn' if turn else 'leg'} did not end within "
                    f"{MAX_MOTION_S:g} s"
                )
            twin.advance(POLL_S)
        twin.advance(p.rest_s)

    def square(self, direction: str) -> None:
        """Drive the four legs and turns of one square (``"cw"`` or ``"ccw"``) from where the robot
        stands, the square in the odometry's frame."""
        if direction not in DIRECTIONS:
            raise ValueError(f"direction: {direction!r} must be cw or ccw")
        sign = 1.0 if direction == "ccw" else -1.0
        side, odo = self.profile.side_m, self.odometry
        x, y, yaw = odo.x_m, odo.y_m, odo.yaw_rad
        self.twin.advance(self.profile.rest_s)
        for _ in range(4):
            x, y = x + side * math.cos(yaw), y + side * math.sin(yaw)
            self._motion(False, x, y, yaw)
            yaw += sign * math.pi / 2
            self._motion(True, x, y, yaw, sign)

    def close(self) -> None:
        """Stop listening to the samples."""
        self._sub.unregister()


def wheel_pose(
    angles_rad: np.ndarray, left_radius_m: float, right_radius_m: float, separation_m: float
) -> tuple[float, float, float]:
    """Pose ``(x_m, y_m, yaw_rad)`` from the start of an ideal encoder odometry: (n, 2) wheel angles
    [left, right], rad, each increment integrated as an arc."""
    d = np.diff(np.asarray(angles_rad, float), axis=0)
    pose = (0.0, 0.0, 0.0)
    for dl, dr in zip((d[:, 0] * left_radius_m).tolist(), (d[:, 1] * right_radius_m).tolist()):
        pose = arc(pose, 0.5 * (dl + dr), (dr - dl) / separation_m, 1.0)
    return pose


def drive_square(twin, direction: str, profile: Profile = Profile(), run: int = 0) -> SquareRun:
    """Drive one square with ``twin`` (fresh: the recorder attached here starts with it) from where
    it stands."""
    from amr_twin.recording.recorder import attach_recorder

    recorder = attach_recorder(twin)
    start = twin.physics.pose()
    driver = SquareDriver(twin, profile)
    try:
        driver.square(direction)
    finally:
        driver.close()
    end = twin.physics.pose()
    c, s = math.cos(start.yaw_rad), math.sin(start.yaw_rad)
    dx, dy = end.x_m - start.x_m, end.y_m - start.y_m
    true_xy = (c * dx + s * dy, -s * dx + c * dy)
    angles = recorder.series().wheel_angle_rad
    w, odo = twin.cfg.wheel, twin.nodes["odometry"]
    assumed = wheel_pose(angles, odo.left_radius_m, odo.right_radius_m, odo.separation_m)
    exact = wheel_pose(
        angles,
        w.radius_m + w.radius_error_left_m,
        w.radius_m + w.radius_error_right_m,
        w.separation_m + w.separation_error_m,
    )
    return SquareRun(
        direction,
        run,
        twin.options.seed,
        (odo.x_m, odo.y_m),
        assumed[:2],
        exact[:2],
        true_xy,
        math.degrees(odo.yaw_rad),
        math.degrees(math.remainder(end.yaw_rad - start.yaw_rad, 2 * math.pi)),
        twin.t_s,
    )
