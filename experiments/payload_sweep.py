"""Payload sweep: step response, duty, support loads, tilt and slip against payload mass and position.

One simulation per (mass, position, command) point, in the empty world; each
point's result is one JSON file ``runs/<key>.json`` written atomically, so a rerun
after an interruption only simulates the missing points (a file made with other
parameters, firmware or duration is redone). A position that puts the payload off
the deck fails the configuration check and is recorded as invalid.

Named positions put the payload box **flush with the deck's edges** (``front``:
against the front edge, ``front-left-corner``: in that corner...), the worst
placements that still lie on the deck; ``X:Y`` gives the box centre in metres.

A point is **safe** when its position is valid, the simulation ran, the static
tip margin is at least :data:`TIP_MARGIN_MIN_M`, no drive wheel ever lost
contact (:data:`~amr_twin.model.statics.CONTACT_MIN_N`), the base tilted at most
:data:`TILT_LIMIT_DEG` and no motor's steady current exceeded the driver's continuous
rating (``driver.continuous_current_a``). The support loads are read every :data:`SAMPLE_S` from the
springs that carry the chassis, as the statics and the rolling resistance take them
(a tyre's ``k_t q + c_t q'``; a caster's spring, or its contact while on its stop):
the contact force of a single step chatters when a wheel carries little (20 N on the
stiff 2 ms contact: 0 in most steps, 100 N and more in between, about 200 Hz) while
the tyre stays compressed; that minimum is kept as ``dyn_min_wheel_contact_n``. The highest safe payload of a position is the largest
mass whose every lighter point (all commands) is safe.

With ``draws`` (:class:`amr_twin.analysis.uncertainty.Draws`, ``--samples N``), every point is
also run once per drawn configuration: its key gains ``_s<i>_<id>`` (the sample's
index and a hash of its drawn values) and its fingerprint covers the drawn
configuration, so a resumed sweep redoes exactly the runs whose parameters changed.
The nominal runs keep the keys of a sweep without samples (and are reused from one).
:mod:`.payload_spread` reports medians, intervals and sensitivities.

Recordings (``record_dir`` / ``mcap_dir`` of :func:`run`): one ``<key>.rrd`` /
``<key>.mcap`` per point **simulated by this call**, written by the process that
simulates it (the Dask workers with a cluster: the folder must be on storage they
share with this machine), through a temporary name and a rename, before the
point's JSON. A resumed sweep does not re-simulate a point that is already done
only because its recording is missing: delete ``runs/<key>.json`` to record it
again. Recording does not change the rows. Invalid positions are not recorded.
"""

from __future__ import annotations

import hashlib
import json
import math
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from amr_twin.model.config import ConfigError, TwinConfig, load_config
from amr_twin.analysis.metrics import step_info
from amr_twin.sim.run import Command
from amr_twin.experiments.chapter5 import TRANSIENT_WINDOW_S, WHEELS, settling_band_rpm

POSITIONS = {"center": (0, 0), "front": (1, 0), "rear": (-1, 0), "left": (0, 1), "right": (0, -1),
             "front-left-corner": (1, 1), "front-right-corner": (1, -1),
             "rear-left-corner": (-1, 1), "rear-right-corner": (-1, -1)}
SAMPLE_S = 0.02           # period of the support-load and tilt samples, s
TIP_MARGIN_MIN_M = 0.02   # static tip margin below which a point is unsafe, m
TILT_LIMIT_DEG = 3.0      # base tilt above which a point is unsafe, deg
MAX_VEL_RPM = 1054.0      # firmware MAX_VEL: open-loop duty = rpm / MAX_VEL
TRACK_TOLERANCE_RPM = 4.0  # |steady error| within the PI dead zone counts as tracking
MAX_MASSES = 1000          # masses per sweep: each is a simulation per position and command
ROWS = 4                   # what a row means (in the fingerprint): 4 = sampled on the loop's record grid in one call; 3 = with the rating judged by; 2 = support loads from the springs; 1: contact forces


def parse_masses(text: str) -> list[float]:
    """``"0:60:5"`` (start:stop:step, stop included) or ``"0,20,40"``, kg."""
    try:
        if ":" in text:
            start, stop, step = (float(v) for v in text.split(":"))
            if not (step > 0 and stop >= start and math.isfinite(stop - start)):
                raise ValueError
            count = math.floor((stop - start) / step + 1e-9) + 1
            if count > MAX_MASSES:
                raise OverflowError(count)
            return [round(start + i * step, 6) for i in range(count)]
        masses = [float(v) for v in text.split(",") if v.strip()]
    except OverflowError as exc:
        raise ValueError(f"--masses {text!r}: {exc.args[0]:.3g} masses; at most {MAX_MASSES} per sweep "
                         "(each is one simulation per position and command)") from None
    except ValueError:
        raise ValueError(f"--masses {text!r}: expected START:STOP:STEP or M1,M2,... in kg") from None
    if not masses or any(not math.isfinite(m) or m < 0 for m in masses):
        raise ValueError(f"--masses {text!r}: masses must be finite and >= 0 kg")
    if len(masses) > MAX_MASSES:
        raise ValueError(f"--masses: {len(masses)} masses; at most {MAX_MASSES} per sweep")
    return masses


def parse_command(text: str) -> Command:
    """One ``--commands`` entry -> Command (see :meth:`Command.parse`)."""
    return Command.parse(text, what="--commands")


def position_xy_m(cfg: TwinConfig, name: str) -> tuple[float, float]:
    """Payload centre of a named position (box flush with the deck edges) or of ``X:Y``, m."""
    if name in POSITIONS:
        dx, dy = POSITIONS[name]
        sx, sy = cfg.payload.size_m[0] / 2, cfg.payload.size_m[1] / 2
        inside = [_micrometres_inside(v) for v in (cfg.chassis.length_m / 2 - sx, cfg.chassis.width_m / 2 - sy)]
        return dx * inside[0] + 0.0, dy * inside[1] + 0.0  # + 0.0: no -0.0
    try:
        x, y = (float(v) for v in name.split(":"))
    except ValueError:
        raise ValueError(f"--positions {name!r}: not one of {', '.join(POSITIONS)} nor X:Y in metres") from None
    return x, y


def _micrometres_inside(v: float) -> float:
    """``v`` rounded to the micrometre, but never beyond it (a drawn deck length ending in 5 at the
    seventh digit would otherwise put a flush payload off the deck)."""
    r = round(v, 6)
    return round(r - 1e-6, 6) if r > v + 1e-9 else r


def with_payload(cfg: TwinConfig, mass_kg: float, xy_m: tuple[float, float]) -> TwinConfig:
    """``cfg`` with another payload, validated again (raises :class:`ConfigError`)."""
    flat: dict = {}

    def walk(node: dict, prefix: str) -> None:
        for key, value in node.items():
            if isinstance(value, dict):
                walk(value, f"{prefix}{key}.")
            else:
                flat[prefix + key] = list(value) if isinstance(value, tuple) else value

    walk(cfg.model_dump(), "")
    flat.update({"payload.mass_kg": mass_kg, "payload.xy_m": list(xy_m)})
    return load_config(overrides=flat)


@dataclass(frozen=True)
class Point:
    """One sweep point (picklable work item)."""

    mass_kg: float
    position: str
    command: str
    duration_s: float
    firmware: str
    cfg: TwinConfig
    rrd_path: str | None = None   # write the point's Rerun recording here (not part of the fingerprint)
    mcap_path: str | None = None  # write the point's ROS 2 topics here
    sample: int | None = None     # index of the drawn configuration ``cfg`` (None: the nominal one)
    sample_id: str = ""           # hash of the sample's drawn values (amr_twin.analysis.uncertainty.Draws.sample_id)

    @property
    def key(self) -> str:
        key = f"m{self.mass_kg:g}kg_{self.position}_{self.command}".replace(":", "_").replace("/", "_")
        return key if self.sample is None else f"{key}_s{self.sample}_{self.sample_id}"

    @property
    def fingerprint(self) -> str:
        from amr_twin.controllers.firmware import firmware_identity  # avr: the sketch's sources count too

        text = (self.cfg.model_dump_json() + f"|{firmware_identity(self.firmware)}|{self.duration_s}"
                + f"|rows {ROWS}")
        return hashlib.sha256(text.encode()).hexdigest()[:16]


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


def _min_wheel_mechanism(cfg: TwinConfig, loads: np.ndarray, vel: np.ndarray, s) -> dict:
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
        mechanism = f"longitudinal load transfer, {ax:+.2f} m/s^2 ({'braking' if ax * vel[i, 0] < 0 else 'accelerating'})"
    return {"dyn_min_wheel": wheel, "dyn_min_wheel_t_s": float(t[i]), "dyn_min_wheel_accel_m_s2": [float(ax), float(ay)],
            "dyn_min_wheel_quasi_static_n": both, "dyn_min_wheel_mechanism": mechanism}


def _electrics(s, duration_s: float) -> dict:
    """Steady motor currents, the battery's current and the energy per metre driven."""
    tail = s.t_s >= 0.75 * duration_s
    power = s.battery_v * s.battery_a
    energy = float(np.sum(0.5 * (power[1:] + power[:-1]) * np.diff(s.t_s)))
    distance = float(np.sum(np.hypot(*np.diff(s.pose[:, :2], axis=0).T)))
    out = {f"{name}_steady_current_a": float(np.mean(np.abs(s.current_a[tail, w]))) for w, name in enumerate(WHEELS)}
    out.update(battery_steady_a=float(np.mean(s.battery_a[tail])), energy_j=energy, distance_m=distance,
               energy_j_per_m=energy / distance if distance > 0.05 else None)
    return out


def _dynamics(point: Point, cfg: TwinConfig) -> dict:
    from amr_twin.sim.loop import Twin, TwinOptions
    from amr_twin.model.statics import CONTACT_MIN_N

    recording = point.rrd_path is not None or point.mcap_path is not None
    # nothing here reads the wheel odometry: without it a point is the same to the bit, ~12 % cheaper
    twin = Twin(cfg, TwinOptions(firmware=point.firmware, world="empty", odometry=recording))
    if recording:
        from amr_twin.recording.rerun_capture import attach

        attach(twin)
    twin.advance_to_us(0)
    command = parse_command(point.command)
    code = command.send(twin)
    if code != 0:
        return {"error": f"command refused (code {code}): {twin.client.last_error}"}
    req = twin.client.last_request
    loads, contact, tilt, vel = [], [], [], []
    physics, every_us = twin.physics, int(round(SAMPLE_S * 1e6))

    def sample(t_us: int) -> bool:
        """Every SAMPLE_S on the loop's record grid, the physics at ``t_us`` (after the rolling
        resistance's sampler, whose springs' loads it reads). The point runs as one call of the
        loop, as ``amr-twin run`` does (stopping the loop every sample moved the results by about
        1e-4 relative and cost about 2 % more CPU)."""
        if t_us % every_us == 0:
            loads.append(list(twin.rolling.loads))  # the springs' loads (module notes)
            contact.append(physics.support_normal_forces_n())
            tilt.append(physics.base_tilt_rad())
            vel.append(physics.base_velocity())
        return False

    twin.samplers.append(sample)
    twin.advance_to_us(int(round(point.duration_s * 1e6)))
    s = twin.recorder.series()
    if recording:
        from amr_twin.recording.rerun_log import record_run
        from amr_twin.sim.run import RunResult

        result = RunResult(commands=[(0.0, command)], codes=[code], wheel_command=None, series=s,
                           sim_s=point.duration_s, wall_s=0.0)
        record_run(twin, rrd_path=point.rrd_path, mcap_path=point.mcap_path, result=result)
    names = list(twin.physics.support_geoms)
    loads = np.array(loads)
    min_load = dict(zip(names, loads.min(axis=0).tolist()))
    out = {"max_tilt_deg": math.degrees(max(tilt)),
           "dyn_min_wheel_n": min(v for n, v in min_load.items() if n.startswith("wheel")),
           "dyn_min_caster_n": min(v for n, v in min_load.items() if n.startswith("caster")),
           "dyn_lifted": ";".join(n for n, v in min_load.items() if v < CONTACT_MIN_N),
           "dyn_min_wheel_contact_n": float(np.min(np.array(contact)[:, :2]))}
    out.update(_min_wheel_mechanism(cfg, loads, np.array(vel), s))
    out.update(_electrics(s, point.duration_s))
    out["wheel_lift_off"] = out["dyn_min_wheel_n"] < CONTACT_MIN_N
    slip = _slip(s, cfg)
    tail = s.t_s >= 0.75 * point.duration_s
    cmd = [req.motionL, req.speedL, req.motionR, req.speedR]
    for w, name in enumerate(WHEELS):
        ref = float(cmd[2 * w]) * float(cmd[2 * w + 1])
        out[f"{name}_reference_rpm"] = ref
        out[f"{name}_max_slip_m_s"] = float(np.max(np.abs(slip[:, w])))
        if ref == 0.0:
            continue
        pub = s.published[w]
        if len(pub) >= 1:
            info = step_info(pub[:, 0], pub[:, 1], abs(ref), settling_band=settling_band_rpm(ref),
                             oscillation_window_s=TRANSIENT_WINDOW_S).as_dict()
            for k in ("delay_s", "rise_s", "peak_s", "settling_s"):
                out[f"{name}_{k}"] = info[k]
            for k in ("overshoot", "steady_error", "oscillation"):
                out[f"{name}_{k}_rpm"] = info[k]
        out[f"{name}_steady_duty"] = float(np.mean(s.pwm_counts[tail, w]) / 255.0)
        out[f"{name}_open_loop_duty"] = abs(ref) / MAX_VEL_RPM
        surface = np.abs(s.true_rpm[tail, w]) * (2 * math.pi / 60) * cfg.wheel.radius_m
        out[f"{name}_steady_slip_ratio"] = float(np.mean(np.abs(slip[tail, w])) / max(np.mean(surface), 1e-6))
    errors = [out.get(f"{n}_steady_error_rpm") for n in WHEELS if out.get(f"{n}_reference_rpm")]
    out["tracks"] = all(e is not None and abs(e) <= TRACK_TOLERANCE_RPM for e in errors)
    return out


def simulate_point(point: Point) -> dict:
    """Statics and one run of a sweep point, as one flat JSON-ready row."""
    from amr_twin.model.build import BuildError
    from amr_twin.sim.physics import DivergenceError
    from amr_twin.model.statics import CONTACT_MIN_N, describe

    wall0 = time.perf_counter()
    row = {"key": point.key, "fingerprint": point.fingerprint, "mass_kg": point.mass_kg,
           "position": point.position, "command": point.command, "valid": True, "error": ""}
    if point.sample is not None:
        row.update(sample=point.sample, sample_id=point.sample_id)
    try:
        xy = position_xy_m(point.cfg, point.position)
        row.update(x_m=xy[0], y_m=xy[1])
        cfg = with_payload(point.cfg, point.mass_kg, xy)
    except (ConfigError, ValueError) as exc:
        row.update(valid=False, error=str(exc), safe=False)
        return row
    try:
        static = describe(cfg)
        loads = static["static_load_n"]
        row.update(total_mass_kg=static["total_mass_kg"], static_tip_margin_m=static["tip_margin_m"],
                   static_min_caster_n=min(v for k, v in loads.items() if k.startswith("caster")),
                   static_lifted=";".join(k for k, v in loads.items() if v < CONTACT_MIN_N),
                   **{f"static_{k}_n": v for k, v in loads.items()})
        row.update(_dynamics(point, cfg))
    except (BuildError, DivergenceError) as exc:
        row["error"] = str(exc).splitlines()[0]
    currents = [row.get(f"{w}_steady_current_a") for w in WHEELS]
    row["current_limit_a"] = cfg.driver.continuous_current_a  # the rating this row is judged by (a draw may move it)
    row["motor_overload"] = any(i is not None and i > cfg.driver.continuous_current_a for i in currents)
    row["safe"] = (not row["error"] and row.get("static_tip_margin_m", -1) >= TIP_MARGIN_MIN_M
                   and not row.get("wheel_lift_off", True) and row.get("max_tilt_deg", 90) <= TILT_LIMIT_DEG
                   and not row["motor_overload"])
    row["wall_s"] = round(time.perf_counter() - wall0, 3)
    return {k: (None if isinstance(v, float) and not math.isfinite(v) else v) for k, v in row.items()}


def run(cfg: TwinConfig, out_dir: Path, masses: list[float], positions: list[str], commands: list[str],
        duration_s: float = 8.0, jobs: int = 1, firmware: str = "faithful", progress: bool = True,
        client=None, record_dir: Path | None = None, mcap_dir: Path | None = None, draws=None) -> dict:
    """Simulate the missing points of the sweep (one file each) and return all rows.

    The points run in this process (``jobs=1``), in ``jobs`` local worker
    processes, or on the Dask cluster of ``client`` (a ``distributed.Client``,
    see :func:`~amr_twin.experiments.executor.connect_dask`); either way each
    result comes back here and is written atomically as it arrives.

    ``record_dir`` / ``mcap_dir``: folders for one ``<key>.rrd`` / ``<key>.mcap``
    recording per point simulated now (points reused from ``runs/`` are not
    re-simulated for a missing recording; see the module notes).

    ``draws``: :class:`amr_twin.analysis.uncertainty.Draws` of ``cfg``'s parameters; each point is
    also run with each drawn configuration (rows with ``sample`` and ``sample_id``, after
    the nominal rows).

    Returns
    -------
    dict : ``{"rows": [...], "simulated": n, "reused": n, "recorded": n, "wall_s": s}``.
    """
    from amr_twin.experiments.executor import run_all, write_json

    for c in commands:
        parse_command(c)
    runs_dir = Path(out_dir) / "runs"
    from amr_twin.recording.rerun_capture import recording_folder

    folders = {kind: recording_folder(folder) for kind, folder in (("rrd", record_dir), ("mcap", mcap_dir))
               if folder is not None}

    def make_point(m: float, p: str, c: str, sample: int | None = None) -> Point:
        extra = {} if sample is None else {"sample": sample, "sample_id": draws.sample_id(sample)}
        point_cfg = cfg if sample is None else configs[sample]
        key = Point(m, p, c, duration_s, firmware, point_cfg, **extra).key
        paths = {f"{kind}_path": str(folder / f"{key}.{kind}") for kind, folder in folders.items()}
        return Point(m, p, c, duration_s, firmware, point_cfg, **paths, **extra)

    configs = [draws.config(cfg, i) for i in range(len(draws))] if draws is not None else []
    points = [make_point(m, p, c, sample) for sample in [None, *range(len(configs))]
              for m in masses for p in positions for c in commands]
    rows, todo = {}, []
    for point in points:
        path = runs_dir / f"{point.key}.json"
        try:
            row = json.loads(path.read_text())
        except (OSError, ValueError):
            row = None
        if row is not None and row.get("fingerprint") == point.fingerprint:
            rows[point.key] = row
        else:
            todo.append(point)
    wall0 = time.perf_counter()
    done = set()
    for item, row in run_all(simulate_point, todo, jobs, "payload sweep", progress, client=client):
        write_json(runs_dir / f"{item.key}.json", row)
        rows[item.key] = row
        done.add(item.key)
    recorded = sum(any((folder / f"{key}.{kind}").exists() for kind, folder in folders.items()) for key in done)
    return {"rows": [rows[p.key] for p in points], "simulated": len(todo), "reused": len(points) - len(todo),
            "recorded": recorded, "wall_s": time.perf_counter() - wall0, "duration_s": duration_s,
            "firmware": firmware, **({"draws": draws} if draws is not None else {})}
