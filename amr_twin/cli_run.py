"""``amr-twin run`` and ``amr-twin client``: the high-level control as in ROS (issue 4).

``amr-twin run linear|angular|motor|stop`` sends one wheel_Command_Client call at
t = 0 and runs the twin for ``--duration-s``; ``amr-twin run --mission FILE`` runs
a timed list of them (format in :mod:`amr_twin.mission`). ``--csv`` writes the
time series, ``--json`` prints one summary object. A speed the client refuses
(code 1) prints the thesis' message on stderr and exits 1; bad input (NaN, a
missing option) exits 2 with one line. Files are written to a temporary name
and renamed, so nothing half-written is left.
"""

from __future__ import annotations

import dataclasses
import json
import logging
import math
from pathlib import Path
from typing import Optional

import numpy as np
import typer

from .atomic_file import write_text
from .cli import ConfigOpt, ParamsOpt, SetOpt, _config, _guard, fail
from .recorder import RunSeries, signed_published

CSV_COLUMNS = ("t_s", "ref_rpm_left", "ref_rpm_right", "pub_rpm_left", "pub_rpm_right",
               "true_rpm_left", "true_rpm_right", "pwm_counts_left", "pwm_counts_right",
               "x_m", "y_m", "yaw_rad", "odom_x_m", "odom_y_m", "odom_yaw_rad",
               "current_a_left", "current_a_right", "battery_a", "battery_v")
"""Columns of ``--csv``: reference RPM (motion x speed of wheel_Command), published RPM
(|wheelN_Vel| x the wheel's commanded direction, held between samples, 0 before the
first), true RPM, analogWrite counts, true pose (world) and odometry pose (odom frame,
held), each motor's (phase) current (+ driving forward), the battery's current and
voltage. Every RPM, here and in ``--json``, is signed: + = the wheel rolls forward."""
CSV_COMMENT = ("# amr-twin run: every rpm column is signed, + = the wheel rolls forward (REP-103); ref_rpm = "
               "motion x speed of wheel_Command, pub_rpm = |wheelN_Vel| x the commanded direction; "
               "x_m, y_m, yaw_rad in the world, odom_* in odom; current_a + driving forward")
"""First line of ``--csv``: ``pandas.read_csv(path, comment="#")``, ``numpy.genfromtxt(path, delimiter=",",
names=True, skip_header=1)``."""

DurationOpt = typer.Option(None, "--duration-s", help="Simulated seconds (default 10; a mission's own).")
PayloadOpt = typer.Option(None, "--payload-kg", help="Payload mass, kg.")
FirmwareOpt = typer.Option("faithful", "--firmware", help="faithful (thesis listings), improved, or avr (the "
                           "sketch compiled with avr-gcc on an emulated ATmega2560; Debian packages in the README).")
SketchOpt = typer.Option(None, "--sketch", help="With --firmware avr: your Arduino sketch folder (FOLDER/FOLDER.ino) "
                         "instead of controllers/arduino/motor_control.")
SeedOpt = typer.Option(0, "--seed", help="Seed of the random parts (rosserial loss, hall jitter).")
CsvOpt = typer.Option(None, "--csv", help="Write the time series here (CSV).")
JsonOpt = typer.Option(False, "--json", help="Print one JSON object.")
RecordOpt = typer.Option(None, "--record", help="Write a Rerun recording here (.rrd; open with `rerun FILE`).")
McapOpt = typer.Option(None, "--mcap", help="Write the ROS 2 topics here (.mcap; Foxglove, ros2 bag).")
WorldOpt = typer.Option("warehouse", "--world", help="World: warehouse, empty (models/worlds/), an MJCF file, "
                        "or a ROS map (map_server YAML + PGM, walls extruded).")
StartOpt = typer.Option("0,0,0", "--start", help="Start pose in the world: X_M,Y_M,YAW_DEG.")
SensorsOpt = typer.Option(False, "--sensors", help="Run the IMU (imu/data_raw, imu/mag, 100 Hz) and the LiDAR "
                          "(scan, 5.5 Hz); recorded with --record/--mcap.")


def checked_firmware(firmware: str, sketch: Optional[Path]) -> str:
    """``--firmware`` and ``--sketch`` as the firmware string; for avr, the sketch built now (one-line error)."""
    from .controllers.firmware import check_avr, firmware_kind

    try:
        kind = firmware_kind(firmware, None if sketch is None else str(sketch))
        check_avr(kind)
    except ValueError as exc:
        fail(str(exc))
    return kind


def _finite(name: str, value: Optional[float], required: bool = True) -> Optional[float]:
    if value is None:
        if required:
            fail(f"{name} is required")
        return None
    if not math.isfinite(value):
        fail(f"{name} {value}: must be a finite number")
    return value


def _held(t_query: np.ndarray, t_sample: np.ndarray, values: np.ndarray, before: float = 0.0) -> np.ndarray:
    """Zero-order hold of samples (t_sample, values) at ``t_query``."""
    idx = np.searchsorted(t_sample, t_query, side="right") - 1
    out = np.where(idx >= 0, values[np.clip(idx, 0, None)] if len(values) else before, before)
    return out.astype(float)


def series_table(series: RunSeries) -> np.ndarray:
    """The ``--csv`` table, shape (n, len(CSV_COLUMNS))."""
    t = series.t_s
    cmd_t = np.array([c[0] for c in series.commands], float)
    cmd = np.array([c[1] for c in series.commands], float).reshape(-1, 4)
    ref = [_held(t, cmd_t, cmd[:, 0] * cmd[:, 1]), _held(t, cmd_t, cmd[:, 2] * cmd[:, 3])]
    pub = [_held(t, p[:, 0], p[:, 1]) for p in (signed_published(series, w) for w in (0, 1))]
    odom = [_held(t, series.odom[:, 0], series.odom[:, k]) for k in (1, 2, 3)]
    return np.column_stack([t, *ref, *pub, series.true_rpm, series.pwm_counts, series.pose, *odom,
                            series.current_a, series.battery_a, series.battery_v])


def _csv_text(series: RunSeries) -> str:
    rows = series_table(series)
    lines = [CSV_COMMENT, ",".join(CSV_COLUMNS)]
    lines += [",".join(f"{v:.9g}" for v in row) for row in rows]
    return "\n".join(lines) + "\n"


def _clean(value):
    if isinstance(value, float) and not math.isfinite(value):
        return None
    if isinstance(value, dict):
        return {k: _clean(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_clean(v) for v in value]
    return value


SIGNED_METRICS = ("reference", "final_value", "peak_value", "steady_error")
"""Step metrics in RPM that carry the sign of the reference (overshoot and band are magnitudes)."""


def _step_metrics(series: RunSeries, wheel: int, reference_rpm: float) -> dict:
    """Step metrics of a wheel's signed published speed, when :mod:`amr_twin.metrics` exists."""
    try:
        from .metrics import step_info
    except ImportError:
        return {}
    pub = signed_published(series, wheel)
    if reference_rpm == 0.0 or len(pub) < 2:
        return {}
    info = step_info(pub[:, 0], pub[:, 1], reference_rpm)
    out = info.as_dict() if hasattr(info, "as_dict") else dataclasses.asdict(info)
    sign = 1.0 if reference_rpm > 0 else -1.0  # step_info measures along the reference
    return {k: (sign * v if k in SIGNED_METRICS else v) for k, v in out.items()}


def summary(result, single: bool) -> dict:
    """The ``--json`` object of a run."""
    series, wc = result.series, result.wheel_command
    code = next((c for c in result.codes if c != 0), 0)
    last_s = series.t_s >= series.t_s[-1] - 1.0  # "final" electrical values: the last second
    wheels = {}
    for w, name in enumerate(("left", "right")):
        reference = wc[2 * w] * wc[2 * w + 1] if wc else 0.0  # signed: motion x speed
        pub = signed_published(series, w)
        entry = {"motion": int(wc[2 * w]) if wc else 0, "reference_rpm": reference,
                 "final_rpm": float(pub[-1, 1]) if len(pub) else 0.0,
                 "true_final_rpm": float(series.true_rpm[-1, w]), "samples": int(len(pub)),
                 "current_a_final": float(series.current_a[last_s, w].mean()),
                 "current_a_peak": float(np.abs(series.current_a[:, w]).max())}
        if single:
            entry.update(_step_metrics(series, w, reference))
        wheels[name] = entry
    commands = [dict(c.describe(), t_s=t) for t, c in result.commands]
    x, y, yaw = (float(v) for v in series.pose[-1])
    odom = series.odom[-1, 1:] if len(series.odom) else np.zeros(3)
    return _clean({
        "command": commands[0] if single else commands, "wheel_command": wc, "code": code,
        "codes": result.codes, "errors": result.errors, "wheels": wheels,
        "final_pose": {"x_m": x, "y_m": y, "yaw_rad": yaw},
        "final_odom_pose": {"x_m": float(odom[0]), "y_m": float(odom[1]), "yaw_rad": float(odom[2])},
        "battery": _battery_summary(series),
        "sim_s": result.sim_s, "wall_s": result.wall_s})


def _battery_summary(series: RunSeries) -> dict:
    """The pack over the run: mean current, final voltage, energy drawn and per metre driven."""
    power = series.battery_v * series.battery_a
    energy = float(np.sum(0.5 * (power[1:] + power[:-1]) * np.diff(series.t_s)))
    distance = float(np.sum(np.hypot(*np.diff(series.pose[:, :2], axis=0).T)))
    return {"battery_a_mean": float(series.battery_a.mean()), "battery_v_final": float(series.battery_v[-1]),
            "energy_j": energy, "distance_m": distance,
            "energy_j_per_m": energy / distance if distance > 0.05 else None}


def _start_pose(text: str) -> tuple[float, float, float]:
    """``X_M,Y_M,YAW_DEG`` to ``(x_m, y_m, yaw_rad)``; a one-line error otherwise."""
    try:
        x_m, y_m, yaw_deg = (float(v) for v in text.split(","))
    except ValueError:
        fail(f"--start {text!r}: expected X_M,Y_M,YAW_DEG, e.g. -7.5,0,0")
    if not all(math.isfinite(v) and abs(v) <= 1e4 for v in (x_m, y_m, yaw_deg)):
        fail(f"--start {text!r}: each value must be finite and within +-10000")
    return x_m, y_m, math.radians(yaw_deg)


def execute(steps, duration_s: float, single: bool, payload_kg, firmware: str, seed: int,
            csv: Optional[Path], as_json: bool, config, params, sets, record: Optional[Path] = None,
            mcap: Optional[Path] = None, sensors: bool = False, world: str = "warehouse",
            start: str = "0,0,0", sketch: Optional[Path] = None) -> None:
    """Run ``steps`` and report; exits non-zero if the client refused a command."""
    from .loop import TwinOptions
    from .run import run_mission

    firmware = checked_firmware(firmware, sketch)
    extra = {}
    if _finite("--payload-kg", payload_kg, required=False) is not None:
        extra["payload.mass_kg"] = payload_kg
    cfg = _config(config, params, sets, extra)
    options = TwinOptions(firmware=firmware, seed=seed, sensors=sensors, world=world,
                          start_xy_yaw=_start_pose(start))
    # the client's refusals are printed below, once
    logging.getLogger("amr_twin.controllers.wheel_command").addHandler(logging.NullHandler())
    if record is None and mcap is None:
        result = _guard(lambda: run_mission(cfg, steps, duration_s, options))
    else:
        from .loop import Twin
        from .rerun_log import attach, record_run

        def recorded():
            twin = Twin(cfg, options)
            attach(twin)
            res = run_mission(cfg, steps, duration_s, options, twin=twin)
            record_run(twin, rrd_path=record, mcap_path=mcap, result=res)
            return res

        result = _guard(recorded)
    if csv is not None:
        write_text(csv, _csv_text(result.series))
    info = summary(result, single)
    if as_json:
        typer.echo(json.dumps(info))
    else:
        wc = result.wheel_command
        if wc:
            typer.echo(f"wheel_Command [{wc[0]:g}, {wc[1]:.5f}, {wc[2]:g}, {wc[3]:.5f}]")
        for name, entry in info["wheels"].items():
            typer.echo(f"{name:5s} reference {entry['reference_rpm']:8.3f} RPM, "
                       f"published {entry['final_rpm']:8.3f} RPM")
        pose = info["final_pose"]
        typer.echo(f"pose x {pose['x_m']:.3f} m, y {pose['y_m']:.3f} m, yaw {pose['yaw_rad']:.3f} rad "
                   f"after {result.sim_s:g} s simulated ({result.wall_s:.2f} s wall)")
    for message in result.errors:
        typer.echo(message, err=True)
    if info["code"] != 0:
        raise typer.Exit(1)


def register(app: typer.Typer) -> None:
    """Add ``run`` (linear, angular, motor, stop, --mission) and ``client`` to the app."""
    from .menu import client
    from .run import Command

    run_app = typer.Typer(add_completion=False, no_args_is_help=False,
                          help="Run wheel commands on the twin, as wheel_Command_Client does.")
    app.add_typer(run_app, name="run")
    app.command(name="client")(client)

    def one(command_factory, duration_s, payload_kg, firmware, seed, csv, as_json, config, params, set_,
            record=None, mcap=None, sensors=False, world="warehouse", start="0,0,0", sketch=None):
        duration_s = _finite("--duration-s", duration_s, required=False)
        try:
            command = command_factory()
        except ValueError as exc:
            fail(str(exc))
        execute([(0.0, command)], 10.0 if duration_s is None else duration_s, True, payload_kg,
                firmware, seed, csv, as_json, config, params, set_, record=record, mcap=mcap, sensors=sensors, world=world, start=start,
                sketch=sketch)

    @run_app.callback(invoke_without_command=True)
    def run(ctx: typer.Context,
            mission: Optional[Path] = typer.Option(None, "--mission", help="Mission YAML (see amr_twin/mission.py)."),
            duration_s: Optional[float] = DurationOpt, payload_kg: Optional[float] = PayloadOpt,
            firmware: str = FirmwareOpt, sketch: Optional[Path] = SketchOpt, seed: int = SeedOpt, csv: Optional[Path] = CsvOpt,
            as_json: bool = JsonOpt, record: Optional[Path] = RecordOpt,
            mcap: Optional[Path] = McapOpt, sensors: bool = SensorsOpt, world: str = WorldOpt, start: str = StartOpt,
            config: Optional[Path] = ConfigOpt,
            params: Optional[Path] = ParamsOpt, set_: Optional[list[str]] = SetOpt) -> None:
        """Run a command kind (linear, angular, motor, stop) or a --mission file."""
        if ctx.invoked_subcommand is not None:
            if mission is not None:
                fail("--mission and a command kind cannot be combined")
            return
        if mission is None:
            fail("give a command (linear, angular, motor, stop) or --mission FILE")
        from .mission import MissionError, load_mission

        try:
            mission_s, steps = load_mission(mission)
        except MissionError as exc:
            fail(str(exc))
        duration_s = _finite("--duration-s", duration_s, required=False)
        execute(steps, mission_s if duration_s is None else duration_s, False, payload_kg, firmware,
                seed, csv, as_json, config, params, set_, record=record, mcap=mcap, sensors=sensors, world=world, start=start,
                sketch=sketch)

    @run_app.command()
    def linear(speed_m_s: Optional[float] = typer.Option(None, "--speed-m-s", help="m/s; negative: backward."),
               duration_s: Optional[float] = DurationOpt, payload_kg: Optional[float] = PayloadOpt,
               firmware: str = FirmwareOpt, sketch: Optional[Path] = SketchOpt, seed: int = SeedOpt, csv: Optional[Path] = CsvOpt,
               as_json: bool = JsonOpt, record: Optional[Path] = RecordOpt,
            mcap: Optional[Path] = McapOpt, sensors: bool = SensorsOpt, world: str = WorldOpt, start: str = StartOpt,
            config: Optional[Path] = ConfigOpt,
               params: Optional[Path] = ParamsOpt, set_: Optional[list[str]] = SetOpt) -> None:
        """Linear motion: both wheels at the same speed (listing 4.4)."""
        speed = _finite("--speed-m-s", speed_m_s)
        one(lambda: Command("linear", speed_m_s=speed), duration_s, payload_kg, firmware, seed, csv,
            as_json, config, params, set_, record=record, mcap=mcap, sensors=sensors, world=world, start=start, sketch=sketch)

    @run_app.command()
    def angular(speed_deg_s: Optional[float] = typer.Option(None, "--speed-deg-s", help="deg/s, CCW +."),
                icc_m: Optional[float] = typer.Option(None, "--icc-m", help="ICC distance, m, + to the left."),
                duration_s: Optional[float] = DurationOpt, payload_kg: Optional[float] = PayloadOpt,
                firmware: str = FirmwareOpt, sketch: Optional[Path] = SketchOpt, seed: int = SeedOpt, csv: Optional[Path] = CsvOpt,
                as_json: bool = JsonOpt, record: Optional[Path] = RecordOpt,
            mcap: Optional[Path] = McapOpt, sensors: bool = SensorsOpt, world: str = WorldOpt, start: str = StartOpt,
            config: Optional[Path] = ConfigOpt,
                params: Optional[Path] = ParamsOpt, set_: Optional[list[str]] = SetOpt) -> None:
        """Rotation about an ICC (listing 4.5; REP-103 signs)."""
        speed, icc = _finite("--speed-deg-s", speed_deg_s), _finite("--icc-m", icc_m)
        one(lambda: Command("angular", speed_deg_s=speed, icc_m=icc), duration_s, payload_kg, firmware,
            seed, csv, as_json, config, params, set_, record=record, mcap=mcap, sensors=sensors, world=world, start=start, sketch=sketch)

    @run_app.command()
    def motor(wheel: Optional[str] = typer.Option(None, "--wheel", help="left or right."),
              direction: Optional[str] = typer.Option(None, "--direction", help="forward or backward."),
              speed_m_s: Optional[float] = typer.Option(None, "--speed-m-s", help="Rim speed, m/s, >= 0."),
              duration_s: Optional[float] = DurationOpt, payload_kg: Optional[float] = PayloadOpt,
              firmware: str = FirmwareOpt, sketch: Optional[Path] = SketchOpt, seed: int = SeedOpt, csv: Optional[Path] = CsvOpt,
              as_json: bool = JsonOpt, record: Optional[Path] = RecordOpt,
            mcap: Optional[Path] = McapOpt, sensors: bool = SensorsOpt, world: str = WorldOpt, start: str = StartOpt,
            config: Optional[Path] = ConfigOpt,
              params: Optional[Path] = ParamsOpt, set_: Optional[list[str]] = SetOpt) -> None:
        """One wheel driven, the other free-spinning (fig. 3.6)."""
        if wheel is None:
            fail("--wheel is required (left or right)")
        if direction is None:
            fail("--direction is required (forward or backward)")
        speed = _finite("--speed-m-s", speed_m_s)
        one(lambda: Command("motor", wheel=wheel, direction=direction, speed_m_s=speed), duration_s,
            payload_kg, firmware, seed, csv, as_json, config, params, set_, record=record, mcap=mcap, sensors=sensors, world=world, start=start, sketch=sketch)

    @run_app.command()
    def stop(duration_s: Optional[float] = DurationOpt, payload_kg: Optional[float] = PayloadOpt,
             firmware: str = FirmwareOpt, sketch: Optional[Path] = SketchOpt, seed: int = SeedOpt, csv: Optional[Path] = CsvOpt,
             as_json: bool = JsonOpt, record: Optional[Path] = RecordOpt,
            mcap: Optional[Path] = McapOpt, sensors: bool = SensorsOpt, world: str = WorldOpt, start: str = StartOpt,
            config: Optional[Path] = ConfigOpt,
             params: Optional[Path] = ParamsOpt, set_: Optional[list[str]] = SetOpt) -> None:
        """Brake both wheels (fig. 3.7)."""
        one(lambda: Command("stop"), duration_s, payload_kg, firmware, seed, csv, as_json, config,
            params, set_, record=record, mcap=mcap, sensors=sensors, world=world, start=start, sketch=sketch)
