"""The eight runs of thesis chapter 5 (§5.1.1-5.1.4) and one run simulated and judged: the raw
series of :func:`simulate` (picklable, for worker processes) and the per-wheel metrics and verdicts
of :func:`analyse` (against :mod:`.criteria`)."""

from __future__ import annotations

from dataclasses import dataclass, field

from amr_twin.analysis.metrics import step_info
from amr_twin.assembly.command import Command
from amr_twin.assembly.twin import TwinOptions
from amr_twin.experiments.chapter5.criteria import (
    TRANSIENT_WINDOW_S,
    WHEELS,
    judge,
    settling_band_rpm,
    step_class,
)
from amr_twin.model.config import TwinConfig, with_values
from amr_twin.recording.run import run_command


@dataclass(frozen=True)
class RunSpec:
    """One chapter 5 experiment."""

    number: int
    title: str
    command: Command
    duration_s: float
    payload_kg: float = 0.0


RUNS = (
    RunSpec(
        1,
        "left wheel forward 1 m/s (76.39 RPM)",
        Command("motor", wheel="left", speed_m_s=1.0),
        18.0,
    ),
    RunSpec(
        2,
        "right wheel forward 1 m/s (76.39 RPM)",
        Command("motor", wheel="right", speed_m_s=1.0),
        18.0,
    ),
    RunSpec(3, "linear forward 0.7 m/s (53.47 RPM)", Command("linear", speed_m_s=0.7), 16.0),
    RunSpec(4, "linear backward 1.2 m/s (91.67 RPM)", Command("linear", speed_m_s=-1.2), 16.0),
    RunSpec(
        5,
        "rotation 60 deg/s, ICC 1 m right",
        Command("angular", speed_deg_s=-60.0, icc_m=-1.0),
        16.0,
    ),
    RunSpec(
        6, "rotation 60 deg/s, ICC 1 m left", Command("angular", speed_deg_s=60.0, icc_m=1.0), 16.0
    ),
    RunSpec(7, "linear forward 0.7 m/s, 20 kg", Command("linear", speed_m_s=0.7), 16.0, 20.0),
    RunSpec(
        8,
        "rotation 60 deg/s, ICC 1 m right, 20 kg",
        Command("angular", speed_deg_s=-60.0, icc_m=-1.0),
        16.0,
        20.0,
    ),
)


@dataclass
class RunJob:
    """One run to simulate: its spec, parameters, firmware and duration (s), recordings to write."""

    spec: RunSpec
    cfg: TwinConfig
    firmware: str
    duration_s: float
    seed: int = 0
    extra: dict = field(default_factory=dict)
    rrd_path: str | None = None  # write the run's Rerun recording here
    mcap_path: str | None = None  # write the run's ROS 2 topics here


def _with_payload(cfg: TwinConfig, mass_kg: float) -> TwinConfig:
    return cfg if mass_kg == cfg.payload.mass_kg else with_values(cfg, {"payload.mass_kg": mass_kg})


def simulate(job: RunJob) -> dict:
    """Run one experiment; return its raw series (picklable, for worker processes)."""
    cfg = _with_payload(job.cfg, job.spec.payload_kg)
    pace_us = job.extra.get("pace_us")
    recording = job.rrd_path is not None or job.mcap_path is not None
    options = TwinOptions(firmware=job.firmware, world="empty", seed=job.seed, visuals=recording)
    if job.rrd_path is None and job.mcap_path is None and pace_us is None:
        result = run_command(cfg, job.spec.command, job.duration_s, options)
    else:
        from amr_twin.assembly.twin import Twin
        from amr_twin.recording.rerun_capture import attach
        from amr_twin.recording.rerun_log import record_run
        from amr_twin.recording.run import run_mission
        from amr_twin.experiments.chapter5.firmware_comparison import pace

        twin = Twin(cfg, options)
        if pace_us is not None:
            pace(twin, pace_us)
        if job.rrd_path is not None or job.mcap_path is not None:
            attach(twin)
        result = run_mission(cfg, [(0.0, job.spec.command)], job.duration_s, options, twin=twin)
        if job.rrd_path is not None or job.mcap_path is not None:
            record_run(twin, rrd_path=job.rrd_path, mcap_path=job.mcap_path, result=result)
    s = result.series
    return {
        "run": job.spec.number,
        "codes": result.codes,
        "errors": result.errors,
        "wheel_command": result.wheel_command,
        "t_command_s": s.commands[0][0] if s.commands else 0.0,
        "t_s": s.t_s,
        "true_rpm": s.true_rpm,
        "published": s.published,
        "pwm_counts": s.pwm_counts,
        "current_a": s.current_a,
        "battery_a": s.battery_a,
        "sim_s": result.sim_s,
        "wall_s": result.wall_s,
        "tyre_timestep": result.tyre_timestep,
    }


def analyse(spec: RunSpec, raw: dict) -> dict:
    """Metrics and verdicts of one run, per driven wheel."""
    wheels = {}
    cmd = raw["wheel_command"] or [0, 0, 0, 0]
    for w, name in enumerate(WHEELS):
        reference = float(cmd[2 * w]) * float(cmd[2 * w + 1])
        if reference == 0.0:
            continue
        band = settling_band_rpm(reference)
        t0 = raw["t_command_s"]
        pub = raw["published"][w]
        kw = dict(t0_s=t0, settling_band=band, oscillation_window_s=TRANSIENT_WINDOW_S)
        sign = 1.0 if reference > 0 else -1.0  # the published speeds are magnitudes (|wheelN_Vel|)
        published = (
            step_info(pub[:, 0], pub[:, 1], abs(reference), **kw).as_dict(sign)
            if len(pub)
            else None
        )
        true = step_info(raw["t_s"], raw["true_rpm"][:, w], reference, **kw).as_dict(sign)
        wheels[name] = {
            "reference_rpm": reference,
            "step_class": step_class(reference),
            "samples": len(pub),
            "published": published,
            "true": true,
            "checks": judge(name, reference, published or {}),
            "true_checks": judge(name, reference, true),
        }
    return {
        "run": spec.number,
        "title": spec.title,
        "command": spec.command.describe(),
        "payload_kg": spec.payload_kg,
        "duration_s": raw["sim_s"],
        "wheel_command": raw["wheel_command"],
        "codes": raw["codes"],
        "errors": raw["errors"],
        "wall_s": raw["wall_s"],
        "wheels": wheels,
        "tyre_timestep": raw.get("tyre_timestep"),
        "raw": raw,
    }
