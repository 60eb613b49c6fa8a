"""One payload sweep point simulated: statics, one run in the empty world, and its flat row.

A point is **safe** when its position is valid, the simulation ran, the static
tip margin is at least :data:`TIP_MARGIN_MIN_M`, no drive wheel ever lost
contact (:data:`~amr_twin.model.statics.CONTACT_MIN_N`), the base tilted at most
:data:`TILT_LIMIT_DEG` and no motor's steady current exceeded the driver's continuous
rating (``driver.continuous_current_a``). The support loads are read every :data:`SAMPLE_S` from the
springs that carry the chassis, as the statics and the rolling resistance take them
(a tyre's ``k_t q + c_t q'``; a caster's spring, or its contact while on its stop):
the contact force of a single step chatters when a wheel carries little (20 N on the
stiff 2 ms contact: 0 in most steps, 100 N and more in between, about 200 Hz) while
the tyre stays compressed; that minimum is kept as ``dyn_min_wheel_contact_n``.

A point with ``rrd_path`` / ``mcap_path`` writes its recording from the process that
simulates it, before its row is returned; recording does not change the row.
"""

from __future__ import annotations

import math
import time

import numpy as np

from amr_twin.model.config import ConfigError, TwinConfig
from amr_twin.analysis.metrics import step_info
from amr_twin.experiments.chapter5.criteria import TRANSIENT_WINDOW_S, WHEELS, settling_band_rpm
from amr_twin.experiments.payload.point import Point, parse_command, position_xy_m, with_payload
from amr_twin.experiments.payload.result import (
    Dynamics,
    Electrics,
    MinWheel,
    PointResult,
    Statics,
    WheelRun,
)

SAMPLE_S = 0.02  # period of the support-load and tilt samples, s
TIP_MARGIN_MIN_M = 0.02  # static tip margin below which a point is unsafe, m
TILT_LIMIT_DEG = 3.0  # base tilt above which a point is unsafe, deg
MAX_VEL_RPM = 1054.0  # firmware MAX_VEL: open-loop duty = rpm / MAX_VEL
TRACK_TOLERANCE_RPM = 4.0  # |steady error| within the PI dead zone counts as tracking
RUNAWAY_RPM = TRACK_TOLERANCE_RPM + MAX_VEL_RPM / 255.0
"""A wheel whose true speed ends further than this from its reference has left it (RPM): beyond the
faithful PI's dead zone and one duty count (4.13 RPM), which is as well as the faithful firmware
holds a wheel (chapter 5's 99.20 RPM wheels end +4.6 and +6.0 RPM off)."""


def _slip(series, cfg: TwinConfig) -> np.ndarray:
    """(n, 2) wheel surface speed minus the ground speed of the wheel centre, m/s."""
    t, pose = series.t_s, series.pose
    if len(t) < 3:
        return np.zeros((len(t), 2))
    vx, vy = np.gradient(pose[:, 0], t), np.gradient(pose[:, 1], t)
    yaw = np.unwrap(pose[:, 2])
    v = vx * np.cos(yaw) + vy * np.sin(yaw)
    omega = np.gradient(yaw, t)
    half = cfg.wheel.separation_m / 2
    ground = np.column_stack([v - omega * half, v + omega * half])
    surface = series.true_rpm * (2 * math.pi / 60) * cfg.wheel.radius_m
    return surface - ground


def _min_wheel_mechanism(cfg: TwinConfig, loads: np.ndarray, vel: np.ndarray, s) -> MinWheel:
    """When and why a drive wheel is least loaded: the accelerations at that instant and the
    quasi-static loads they give (:func:`amr_twin.model.statics.solve` with d'Alembert's force).

    ``loads`` (k, 6) support loads and ``vel`` (k, 6) base velocities (world linear, body
    angular) every :data:`SAMPLE_S`; ``s`` the run's series (for the yaw).
    """
    from amr_twin.model.statics import solve

    i, w = np.unravel_index(np.argmin(loads[:, :2]), loads[:, :2].shape)
    t = SAMPLE_S * (np.arange(len(loads)) + 1)
    yaw = np.interp(t, s.t_s, np.unwrap(s.pose[:, 2]))
    acc_world = np.gradient(vel[:, :2], SAMPLE_S, axis=0)
    c, sn = np.cos(yaw[i]), np.sin(yaw[i])
    ax, ay = c * acc_world[i, 0] + sn * acc_world[i, 1], -sn * acc_world[i, 0] + c * acc_world[i, 1]
    wheel = WHEELS[w]
    static = solve(cfg).loads_n[f"wheel_{wheel}"]
    both = solve(cfg, (ax, ay)).loads_n[f"wheel_{wheel}"]
    lateral = solve(cfg, (0.0, ay)).loads_n[f"wheel_{wheel}"] - static
    longitudinal = solve(cfg, (ax, 0.0)).loads_n[f"wheel_{wheel}"] - static
    if max(abs(lateral), abs(longitudinal)) < 0.05 * static:
        mechanism = "static load split"
    elif abs(lateral) >= abs(longitudinal):
        mechanism = f"lateral load transfer, {ay:+.2f} m/s^2 (turning)"
    else:
        mechanism = (
            f"longitudinal load transfer, {ax:+.2f} m/s^2 "
            f"({'braking' if ax * vel[i, 0] < 0 else 'accelerating'})"
        )
    return MinWheel(wheel, float(t[i]), [float(ax), float(ay)], both, mechanism)


def _electrics(s, duration_s: float) -> Electrics:
    """Steady motor currents, the battery's current and the energy per metre driven."""
    tail = s.t_s >= 0.75 * duration_s
    power = s.battery_v * s.battery_a
    energy = float(np.sum(0.5 * (power[1:] + power[:-1]) * np.diff(s.t_s)))
    distance = float(np.sum(np.hypot(*np.diff(s.pose[:, :2], axis=0).T)))
    currents = tuple(float(np.mean(np.abs(s.current_a[tail, w]))) for w in range(len(WHEELS)))
    return Electrics(
        currents,
        float(np.mean(s.battery_a[tail])),
        energy,
        distance,
        energy / distance if distance > 0.05 else None,
    )


def _dynamics(point: Point, cfg: TwinConfig) -> tuple[Dynamics | None, str]:
    """The run of ``point`` in the empty world, or None and why the command was refused."""
    from amr_twin.model.statics import CONTACT_MIN_N
    from amr_twin.recording.recorder import attach_recorder
    from amr_twin.assembly.twin import Twin, TwinOptions

    recording = point.rrd_path is not None or point.mcap_path is not None
    # nothing here reads the wheel odometry or draws the robot: without them a point is the same to
    # the bit, ~12 % and ~15 % cheaper
    twin = Twin(
        cfg,
        TwinOptions(
            firmware=point.firmware,
            world="empty",
            nodes=("odometry",) if recording else (),
            visuals=recording,
        ),
    )
    recorder = attach_recorder(twin)
    if recording:
        from amr_twin.recording.rerun_capture import attach

        attach(twin)
    twin.advance_to_us(0)
    command = parse_command(point.command)
    code = command.send(twin)
    if code != 0:
        return None, f"command refused (code {code}): {twin.client.last_error}"
    req = twin.client.last_request
    # every SAMPLE_S on the loop's record grid, after the rolling resistance's update at the same
    # instant: the springs' loads it used, the supports' contact forces, the world z of the
    # base's z axis (the tilt's cosine) and the base velocity (RollingResistance.support_rows).
    # The point runs as one call of the loop, as ``amr-twin run`` does (stopping the loop every
    # sample moved the results by about 1e-4 relative and cost about 2 % more CPU).
    support = twin.rolling.support_rows(int(round(SAMPLE_S * 1e6)))
    twin.on_grid(support)
    twin.advance_to_us(int(round(point.duration_s * 1e6)))
    rows = support.take()  # the instant, then the values
    loads, contact, up_z, vel = rows[:, 1:7], rows[:, 7:13], rows[:, 13], rows[:, 14:20]
    s = recorder.series()
    if recording:
        from amr_twin.recording.rerun_log import record_run
        from amr_twin.recording.run import RunResult

        result = RunResult(
            commands=[(0.0, command)],
            codes=[code],
            wheel_command=None,
            series=s,
            sim_s=point.duration_s,
            wall_s=0.0,
        )
        record_run(twin, rrd_path=point.rrd_path, mcap_path=point.mcap_path, result=result)
    names = list(twin.physics.support.geoms)
    min_load = dict(zip(names, loads.min(axis=0).tolist()))
    min_wheel_n = min(v for n, v in min_load.items() if n.startswith("wheel"))
    slip = _slip(s, cfg)
    tail = s.t_s >= 0.75 * point.duration_s
    cmd = [req.motionL, req.speedL, req.motionR, req.speedR]
    wheels = tuple(
        _wheel_run(w, float(cmd[2 * w]) * float(cmd[2 * w + 1]), s, slip, tail, cfg)
        for w in range(len(WHEELS))
    )
    errors = [(w.step or {}).get("steady_error_rpm") for w in wheels if w.reference_rpm]
    return (
        Dynamics(
            max_tilt_deg=math.degrees(
                math.acos(max(-1.0, min(1.0, float(up_z.min()))))
            ),  # acos falls: the largest tilt
            min_wheel_n=min_wheel_n,
            min_caster_n=min(v for n, v in min_load.items() if n.startswith("caster")),
            lifted=";".join(n for n, v in min_load.items() if v < CONTACT_MIN_N),
            min_wheel_contact_n=float(np.min(contact[:, :2])),
            min_wheel=_min_wheel_mechanism(cfg, loads, vel, s),
            electrics=_electrics(s, point.duration_s),
            wheel_lift_off=min_wheel_n < CONTACT_MIN_N,
            wheels=wheels,
            tracks=all(e is not None and abs(e) <= TRACK_TOLERANCE_RPM for e in errors),
            tyre_timestep_s=twin.tyre_timestep.timestep_s if twin.tyre_timestep.halvings else None,
        ),
        "",
    )


def _wheel_run(
    w: int, ref: float, s, slip: np.ndarray, tail: np.ndarray, cfg: TwinConfig
) -> WheelRun:
    """Wheel ``w`` of the run, its signed reference ``ref`` RPM: the step of its published speed and
    its steady state (over ``tail``, the last quarter)."""
    name, max_slip = WHEELS[w], float(np.max(np.abs(slip[:, w])))
    if ref == 0.0:
        return WheelRun(name, ref, max_slip)
    pub, step = s.published[w], None
    if len(pub) >= 1:
        info = step_info(
            pub[:, 0],
            pub[:, 1],
            abs(ref),
            settling_band=settling_band_rpm(ref),
            oscillation_window_s=TRANSIENT_WINDOW_S,
        ).as_dict()
        step = {k: info[k] for k in ("delay_s", "rise_s", "peak_s", "settling_s")}
        step.update({f"{k}_rpm": info[k] for k in ("overshoot", "steady_error", "oscillation")})
    sign = (
        1.0 if ref > 0 else -1.0
    )  # the true speed's offset along the reference, as the published one's
    surface = np.abs(s.true_rpm[tail, w]) * (2 * math.pi / 60) * cfg.wheel.radius_m
    steady = {
        "true_steady_error_rpm": float(sign * np.mean(s.true_rpm[tail, w]) - abs(ref)),
        "steady_duty": float(np.mean(s.pwm_counts[tail, w]) / 255.0),
        "open_loop_duty": abs(ref) / MAX_VEL_RPM,
        "steady_slip_ratio": float(np.mean(np.abs(slip[tail, w])) / max(np.mean(surface), 1e-6)),
    }
    return WheelRun(name, ref, max_slip, step, steady)


def simulate_point(point: Point) -> PointResult:
    """Statics and one run of a sweep point (:meth:`PointResult.as_json`: its flat JSON-ready
    row)."""
    from amr_twin.model.build import BuildError
    from amr_twin.sim.physics import DivergenceError
    from amr_twin.model.statics import CONTACT_MIN_N, describe

    wall0 = time.perf_counter()
    res = PointResult(
        point.key,
        point.fingerprint,
        point.mass_kg,
        point.position,
        point.command,
        sample=point.sample,
        sample_id=point.sample_id if point.sample is not None else None,
    )
    try:
        res.xy_m = position_xy_m(point.cfg, point.position)
        cfg = with_payload(point.cfg, point.mass_kg, res.xy_m)
    except (ConfigError, ValueError) as exc:
        res.valid, res.error = False, str(exc)
        return res
    try:
        static = describe(cfg)
        loads = static["static_load_n"]
        res.statics = Statics(
            static["total_mass_kg"],
            static["tip_margin_m"],
            min(v for k, v in loads.items() if k.startswith("caster")),
            ";".join(k for k, v in loads.items() if v < CONTACT_MIN_N),
            dict(loads),
        )
        res.dynamics, res.error = _dynamics(point, cfg)
    except (BuildError, DivergenceError) as exc:
        res.error = str(exc).splitlines()[0]
    currents = res.dynamics.electrics.steady_current_a if res.dynamics is not None else ()
    res.current_limit_a = (
        cfg.driver.continuous_current_a
    )  # the rating this row is judged by (a draw may move it)
    res.motor_overload = any(i > cfg.driver.continuous_current_a for i in currents)
    d = res.dynamics
    res.safe = (
        not res.error
        and res.statics is not None
        and res.statics.tip_margin_m >= TIP_MARGIN_MIN_M
        and d is not None
        and not d.wheel_lift_off
        and d.max_tilt_deg <= TILT_LIMIT_DEG
        and not res.motor_overload
    )
    res.wall_s = round(time.perf_counter() - wall0, 3)
    return res


def simulate_points(points: tuple[Point, ...]) -> list[dict]:
    """The rows (:meth:`PointResult.as_json`) of :func:`simulate_point` of each point, in order, in
    this process (a work item of the sweep)."""
    return [simulate_point(point).as_json() for point in points]
