"""The calibration's targets: what the twin must reproduce, and the twin's value of each.

Reasons and measurements: docs/explanation/validation.md#amr_twincalibrationtargets."""

from __future__ import annotations

import csv
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from amr_twin.model.config import TwinConfig
from amr_twin.assembly.twin import TwinOptions
from amr_twin.analysis.metrics import step_info
from amr_twin.assembly.command import Command
from amr_twin.recording.run import run_command

BENCH_RPM = 71.5
BENCH_CURRENT_A = 0.38
BENCH_SUPPLY_V = 36.0  # listing 4.1's "Max amps are 250/36": a 36 V supply
BENCH_QUANTITY = "motor"
"""What the bench point's 0.38 A is taken to be: "motor" (phase) or "supply" current."""
CALIBRATION_S = 10.0


@dataclass(frozen=True)
class Target:
    """One measured feature the twin must reproduce: value and its uncertainty (1 sigma)."""

    name: str
    value: float
    sigma: float
    unit: str


@dataclass(frozen=True)
class _RunTargets:
    command: Command
    wheels: tuple[int, ...]
    targets: tuple[Target, ...]


# chapter 5 runs 1-6; §5.1.3: delay 0.5 s / rise 1 s above 75 RPM, 0.2 / 0.5 s below
THESIS_RUNS = (
    _RunTargets(
        Command("motor", wheel="left", speed_m_s=1.0),
        (0,),
        (
            Target("run1.left.steady_error", 0.0, 1.0, "RPM"),
            Target("run1.left.overshoot", 1.5, 1.0, "RPM"),
            Target("run1.left.true_delay", 0.5, 0.15, "s"),
            Target("run1.left.true_rise", 1.0, 0.2, "s"),
        ),
    ),
    _RunTargets(
        Command("motor", wheel="right", speed_m_s=1.0),
        (1,),
        (
            Target("run2.right.steady_error", 0.0, 1.0, "RPM"),
            Target("run2.right.overshoot", 4.0, 1.0, "RPM"),
            Target("run2.right.true_delay", 0.5, 0.15, "s"),
            Target("run2.right.true_rise", 1.0, 0.2, "s"),
        ),
    ),
    # run 3: the right wheel's timings are left out: listing 4.10's blocking ramp starts it
    # after the left one (about 0.5 s later), whatever the plant
    _RunTargets(
        Command("linear", speed_m_s=0.7),
        (0, 1),
        (
            Target("run3.left.steady_error", 0.0, 1.0, "RPM"),
            Target("run3.right.steady_error", 0.0, 1.0, "RPM"),
            Target("run3.left.true_delay", 0.2, 0.15, "s"),
            Target("run3.left.true_rise", 0.5, 0.2, "s"),
        ),
    ),
    # runs 4-6, the faster steps: each wheel's steady speed ("almost perfect track" in every run)
    *(
        _RunTargets(
            c,
            (0, 1),
            (
                Target(f"run{n}.left.steady_error", 0.0, 1.0, "RPM"),
                Target(f"run{n}.right.steady_error", 0.0, 1.0, "RPM"),
            ),
        )
        for n, c in (
            (4, Command("linear", speed_m_s=-1.2)),
            (5, Command("angular", speed_deg_s=-60.0, icc_m=-1.0)),
            (6, Command("angular", speed_deg_s=60.0, icc_m=1.0)),
        )
    ),
)
BENCH_TARGETS = (
    Target("bench.left.current", BENCH_CURRENT_A, 0.04, "A"),
    Target("bench.right.current", BENCH_CURRENT_A, 0.04, "A"),
)
MISSING_PENALTY = 10.0
"""Residual (in sigmas) of a feature the run does not show (no sample, level never reached)."""


# ------------------------------------------------------------------------- the bench point
def bench_current_a(
    cfg: TwinConfig,
    wheel: int,
    quantity: str = BENCH_QUANTITY,
    rpm: float = BENCH_RPM,
    supply_v: float = BENCH_SUPPLY_V,
) -> float:
    """Current of one motor turning its free wheel steadily at ``rpm``, A.

    Steady and unloaded, the motor's torque ``Ke I`` balances its own friction and
    damping; the driver's input current follows from the power ``(Ke w + R I) I`` at
    ``supply_v`` plus its quiescent current.
    """
    m = (cfg.motor_left, cfg.motor_right)[wheel]
    w = rpm * 2 * math.pi / 60
    i_motor = (m.friction_nm + m.damping_nm_s_rad * w) / m.ke_v_s_rad
    if quantity == "motor":
        return i_motor
    if quantity == "supply":
        return (
            m.ke_v_s_rad * w + m.resistance_ohm * i_motor
        ) * i_motor / supply_v + cfg.driver.quiescent_current_a
    raise ValueError(f"quantity: {quantity!r} must be motor or supply")


# ------------------------------------------------------------------------- chapter 5 features
def command_reference(cfg: TwinConfig, command: Command) -> tuple[float, float]:
    """Signed wheel references (RPM) the client sends for ``command``."""
    r = command.dry_run(cfg).last_request
    return (r.motionL * r.speedL, r.motionR * r.speedR) if r is not None else (0.0, 0.0)


def _run_features(job: tuple[TwinConfig, _RunTargets]) -> dict[str, float]:
    """Simulate one chapter 5 run and measure its features (NaN when not measurable)."""
    cfg, spec = job
    series = run_command(
        cfg, spec.command, CALIBRATION_S, TwinOptions(world="empty", visuals=False)
    ).series
    refs = command_reference(cfg, spec.command)
    prefix = spec.targets[0].name.split(".")[0]
    out = {}
    for w in spec.wheels:
        name = ("left", "right")[w]
        ref = refs[w]
        pub = series.published[w]
        if len(pub) >= 2:
            info = step_info(pub[:, 0], pub[:, 1], abs(ref))
            late = pub[pub[:, 0] > 0.5 * CALIBRATION_S, 1]
            out[f"{prefix}.{name}.steady_error"] = (
                float(late.mean() - abs(ref)) if len(late) else math.nan
            )
            out[f"{prefix}.{name}.overshoot"] = info.overshoot
        true = step_info(series.t_s, series.true_rpm[:, w], ref)
        out[f"{prefix}.{name}.true_delay"] = true.delay_s
        out[f"{prefix}.{name}.true_rise"] = true.rise_s
    return out


def thesis_features(cfg: TwinConfig, pool=None, bench: str = BENCH_QUANTITY) -> dict[str, float]:
    """The twin's value of every thesis target (name -> value)."""
    jobs = [(cfg, spec) for spec in THESIS_RUNS]
    results = (
        list(pool.map(_run_features, jobs))
        if pool is not None
        else [_run_features(j) for j in jobs]
    )
    out = {
        name: bench_current_a(cfg, w, bench) for w, name in enumerate(t.name for t in BENCH_TARGETS)
    }
    for r in results:
        out.update(r)
    return out


def thesis_targets() -> list[Target]:
    return list(BENCH_TARGETS) + [t for spec in THESIS_RUNS for t in spec.targets]


def weighted_residuals(features: dict[str, float], targets: list[Target]) -> np.ndarray:
    """(len(targets),) ``(twin - target) / sigma``; a missing feature costs
    :data:`MISSING_PENALTY`."""
    out = []
    for t in targets:
        v = features.get(t.name, math.nan)
        out.append((v - t.value) / t.sigma if math.isfinite(v) else MISSING_PENALTY)
    return np.array(out)


def thesis_residual(cfg: TwinConfig, bench: str = BENCH_QUANTITY) -> float:
    """Sum of squared weighted residuals of the thesis targets (chi^2) for ``cfg``."""
    return float(
        np.sum(weighted_residuals(thesis_features(cfg, bench=bench), thesis_targets()) ** 2)
    )


# ------------------------------------------------------------------------- a log of the robot
MAX_LOG_BYTES = 64 * 1024 * 1024
"""Largest log read, bytes (an hour of both wheels at 100 Hz is ~30 MB)."""
MAX_LOG_RPM = 2000.0
"""Largest wheel speed a log may give, RPM (the hub motors' no-load speed is below 1000 RPM)."""
LOG_TAIL_S = 0.5
"""Each command of a log is simulated until its last sample plus this, s."""


def read_log(path: Path) -> dict[str, dict[int, np.ndarray]]:
    """Group a log by command: {command: {wheel: (k, 2) t_s, rpm}}.

    Refused with one line naming the file (and the line): a file that is no UTF-8 text, a folder, a
    device or larger than :data:`MAX_LOG_BYTES`; a row of another number of fields than the header;
    a value that is not a number, not finite, a time outside ``[0, MAX_RUN_S - 0.5]`` s or a speed
    beyond :data:`MAX_LOG_RPM`; commands whose runs together simulate more than ``MAX_RUN_S`` per
    evaluation of the fit.
    """
    import io

    from amr_twin.model.yaml_file import read_text
    from amr_twin.sim.bounds import MAX_RUN_S

    text = read_text(path, "", ValueError, limit=MAX_LOG_BYTES).removeprefix(
        "\ufeff"
    )  # spreadsheets' BOM
    groups: dict[str, dict[int, list]] = {}
    reader = csv.DictReader(io.StringIO(text, newline=""))
    missing = {"t_s", "wheel", "rpm", "command"} - set(reader.fieldnames or [])
    if missing:
        raise ValueError(
            f"{path}: missing column(s) {sorted(missing)} (need t_s, wheel, rpm, command)"
        )
    last_t = MAX_RUN_S - LOG_TAIL_S
    try:
        rows = list(enumerate(reader, 2))
    except csv.Error as exc:
        raise ValueError(f"{path}:{reader.line_num}: not a CSV row ({exc})") from None
    for line, row in rows:
        if None in row or any(row[k] is None for k in ("t_s", "wheel", "rpm", "command")):
            fields = (
                len(reader.fieldnames)
                + len(row.get(None) or [])
                - sum(v is None for v in row.values())
            )
            raise ValueError(
                f"{path}:{line}: {fields} field(s); every row has the header's "
                f"{len(reader.fieldnames)} ({', '.join(reader.fieldnames)})"
            )
        try:
            t, rpm = float(row["t_s"]), float(row["rpm"])
        except ValueError:
            raise ValueError(f"{path}:{line}: t_s and rpm must be numbers") from None
        wheel = {"0": 0, "left": 0, "1": 1, "right": 1}.get(row["wheel"].strip())
        if wheel is None or not (math.isfinite(t) and math.isfinite(rpm)):
            raise ValueError(f"{path}:{line}: wheel must be left/right/0/1 and values finite")
        if not 0.0 <= t <= last_t:
            raise ValueError(
                f"{path}:{line}: t_s {t:g} must lie in [0, {last_t:g}] s (a command is simulated "
                f"until its last sample + {LOG_TAIL_S:g} s, at most {MAX_RUN_S:g} s)"
            )
        if abs(rpm) > MAX_LOG_RPM:
            raise ValueError(f"{path}:{line}: rpm {rpm:g} must lie within +-{MAX_LOG_RPM:g} RPM")
        Command.parse(row["command"], what=f"{path}:{line}: command")
        groups.setdefault(row["command"].strip(), {}).setdefault(wheel, []).append((t, rpm))
    if not groups:
        raise ValueError(f"{path}: no samples")
    total_s = sum(
        max(t for v in wheels.values() for t, _ in v) + LOG_TAIL_S for wheels in groups.values()
    )
    if total_s > MAX_RUN_S:
        raise ValueError(
            f"{path}: its {len(groups)} commands are simulated for {total_s:g} s in all at every "
            f"evaluation of the fit; at most {MAX_RUN_S:g} s (split the log)"
        )
    return {
        cmd: {w: np.array(sorted(v)) for w, v in wheels.items()} for cmd, wheels in groups.items()
    }


def log_residuals(cfg: TwinConfig, log: dict[str, dict[int, np.ndarray]]) -> np.ndarray:
    """Twin minus log at the log's sample times, RPM (1 RPM per sample = 1 sigma)."""
    errors = []
    for text, wheels in log.items():
        duration = max(float(v[:, 0].max()) for v in wheels.values()) + LOG_TAIL_S
        series = run_command(
            cfg, Command.parse(text), duration, TwinOptions(world="empty", visuals=False)
        ).series
        for w, samples in wheels.items():
            pub = series.published[w]
            if len(pub) < 2:
                errors.append(np.full(len(samples), MISSING_PENALTY))
                continue
            twin = np.interp(samples[:, 0], pub[:, 0], pub[:, 1], left=0.0)
            errors.append(twin - samples[:, 1])
    return np.concatenate(errors)
