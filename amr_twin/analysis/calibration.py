"""Calibration: identify the drive's unknowns from measured data, with their uncertainty.

Unknowns (the thesis gives none of them): the driver's gain (the ZS-X11D1 reads the
PWM as a speed demand), each motor's back-EMF constant ``Ke`` and its own dry
friction (bearings, seals, cogging). Every other drive parameter keeps its sourced
value (winding resistance, iron-loss damping, tyre and caster rolling resistance).
Two targets:

- ``thesis``: weighted residuals, each ``(twin - thesis) / sigma``:

  * the bench point of listing 4.1 (``0,38 Amp --> 71,5 RPM``, one wheel free on the
    work station of fig. 5.1): each motor's current turning its free wheel at
    71.5 RPM. Read as the motor (phase) current (:data:`BENCH_QUANTITY`; the reasons
    are in docs/validation.md): steady, the torque ``Ke I`` balances the motor's
    friction and damping, so the point pins the motor's own drag;
  * chapter 5 runs 1-3 (faithful firmware, 10 s each, empty world): the published
    speed's steady error (the thesis: an "almost perfect track") and overshoot
    (right about 4 RPM, left about 1.5), and the delay and rise times of the true
    wheel speed against §5.1.3's figures (the time constant ``J R / Ke^2`` sets them,
    which pins ``Ke`` given ``R``).

- a log ``LOG.csv`` of real wheel speeds (columns ``t_s, wheel, rpm, command``;
  ``command`` as in ``amr-twin sweep``: ``linear:0.7``, ``angular:-60:-1``,
  ``motor:left:1.0`` or ``motor:left:forward:1.0``): each command's run is simulated
  for the log's duration and the published speeds are compared with the log at the
  log's times (1 RPM per sample).

The fit is scipy's bounded ``least_squares`` (trust region reflective) in parameters
scaled to their bounds; its Jacobian at the optimum gives each parameter's standard
uncertainty and the correlations (``(J^T J)^-1``: the targets' sigmas are their
uncertainties). The result is an override file for ``--params``.
"""

from __future__ import annotations

import csv
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import yaml

from amr_twin.recording.atomic_file import write_text
from amr_twin.model.config import TwinConfig, load_config
from amr_twin.sim.loop import TwinOptions
from amr_twin.analysis.metrics import step_info
from amr_twin.sim.run import Command, run_command

PARAMETERS = {  # dotted key: (lower, upper) bounds, physically plausible
    "driver.gain": (0.8, 4.0),
    "motor_left.ke_v_s_rad": (0.35, 0.70),   # 36 V hub motors with 500-1000 RPM no load
    "motor_right.ke_v_s_rad": (0.35, 0.70),
    "motor_left.friction_nm": (0.0, 2.0),
    "motor_right.friction_nm": (0.0, 2.0),
}
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


THESIS_RUNS = (  # chapter 5 runs 1-3; §5.1.3: delay 0.5 s / rise 1 s above 75 RPM, 0.2 / 0.5 s below
    _RunTargets(Command("motor", wheel="left", speed_m_s=1.0), (0,), (
        Target("run1.left.steady_error", 0.0, 1.0, "RPM"), Target("run1.left.overshoot", 1.5, 1.0, "RPM"),
        Target("run1.left.true_delay", 0.5, 0.15, "s"), Target("run1.left.true_rise", 1.0, 0.2, "s"))),
    _RunTargets(Command("motor", wheel="right", speed_m_s=1.0), (1,), (
        Target("run2.right.steady_error", 0.0, 1.0, "RPM"), Target("run2.right.overshoot", 4.0, 1.0, "RPM"),
        Target("run2.right.true_delay", 0.5, 0.15, "s"), Target("run2.right.true_rise", 1.0, 0.2, "s"))),
    # run 3: the right wheel's timings are left out: listing 4.10's blocking ramp starts it
    # after the left one (about 0.5 s later), whatever the plant
    _RunTargets(Command("linear", speed_m_s=0.7), (0, 1), (
        Target("run3.left.steady_error", 0.0, 1.0, "RPM"), Target("run3.right.steady_error", 0.0, 1.0, "RPM"),
        Target("run3.left.true_delay", 0.2, 0.15, "s"), Target("run3.left.true_rise", 0.5, 0.2, "s"))),
)
BENCH_TARGETS = (Target("bench.left.current", BENCH_CURRENT_A, 0.04, "A"),
                 Target("bench.right.current", BENCH_CURRENT_A, 0.04, "A"))
MISSING_PENALTY = 10.0
"""Residual (in sigmas) of a feature the run does not show (no sample, level never reached)."""


@dataclass
class Fit:
    """Result of a calibration: values, 1-sigma uncertainties, correlations, residuals."""

    values: dict[str, float]
    sigma: dict[str, float]
    correlation: dict[str, dict[str, float]]
    residual: float                 # sum of squared weighted residuals (chi^2)
    evaluations: int
    target: str
    features: list[dict] = field(default_factory=list)  # name, twin, target, sigma, unit, weighted

    def override_tree(self) -> dict:
        """Nested YAML tree for ``--params`` (values with unit and source)."""
        from amr_twin.model.config import parameter_table

        units = {key: unit for key, _v, unit, _s in parameter_table()}
        tree: dict = {}
        for key, value in self.values.items():
            section, name = key.split(".")
            tree.setdefault(section, {})[name] = {
                "value": round(float(value), 5), "unit": units[key],
                "source": f"calibrated: against {self.target}, 1 sigma {self.sigma[key]:.2g}, residual "
                          f"{self.residual:.3g} ({self.evaluations} evaluations, amr-twin calibrate)"}
        return tree

    def config(self, base: TwinConfig) -> TwinConfig:
        """``base`` with the fitted values."""
        return _with(base, self.values)

    def report(self) -> dict:
        """JSON-ready summary."""
        return {"target": self.target, "residual": self.residual, "evaluations": self.evaluations,
                "values": self.values, "sigma": self.sigma, "correlation": self.correlation,
                "features": self.features}


# ------------------------------------------------------------------------- the bench point
def bench_current_a(cfg: TwinConfig, wheel: int, quantity: str = BENCH_QUANTITY,
                    rpm: float = BENCH_RPM, supply_v: float = BENCH_SUPPLY_V) -> float:
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
        return (m.ke_v_s_rad * w + m.resistance_ohm * i_motor) * i_motor / supply_v + cfg.driver.quiescent_current_a
    raise ValueError(f"quantity: {quantity!r} must be motor or supply")


# ------------------------------------------------------------------------- chapter 5 features
def command_reference(cfg: TwinConfig, command: Command) -> tuple[float, float]:
    """Signed wheel references (RPM) the client sends for ``command``."""
    from amr_twin.ros.bus import Bus
    from amr_twin.sim.clock import VirtualClock
    from amr_twin.controllers.wheel_command import WheelCommandClient, WheelCommandService

    bus = Bus(VirtualClock())
    WheelCommandService(bus)
    client = WheelCommandClient(bus, wheel_radius_m=cfg.wheel.radius_m, half_separation_m=cfg.wheel.separation_m / 2)
    command.send(type("T", (), {"client": client})())
    r = client.last_request
    return (r.motionL * r.speedL, r.motionR * r.speedR) if r is not None else (0.0, 0.0)


def _run_features(job: tuple[TwinConfig, _RunTargets]) -> dict[str, float]:
    """Simulate one chapter 5 run and measure its features (NaN when not measurable)."""
    cfg, spec = job
    series = run_command(cfg, spec.command, CALIBRATION_S, TwinOptions(world="empty")).series
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
            out[f"{prefix}.{name}.steady_error"] = float(late.mean() - abs(ref)) if len(late) else math.nan
            out[f"{prefix}.{name}.overshoot"] = info.overshoot
        true = step_info(series.t_s, series.true_rpm[:, w], ref)
        out[f"{prefix}.{name}.true_delay"] = true.delay_s
        out[f"{prefix}.{name}.true_rise"] = true.rise_s
    return out


def thesis_features(cfg: TwinConfig, pool=None, bench: str = BENCH_QUANTITY) -> dict[str, float]:
    """The twin's value of every thesis target (name -> value)."""
    jobs = [(cfg, spec) for spec in THESIS_RUNS]
    results = list(pool.map(_run_features, jobs)) if pool is not None else [_run_features(j) for j in jobs]
    out = {name: bench_current_a(cfg, w, bench) for w, name in enumerate(t.name for t in BENCH_TARGETS)}
    for r in results:
        out.update(r)
    return out


def thesis_targets() -> list[Target]:
    return list(BENCH_TARGETS) + [t for spec in THESIS_RUNS for t in spec.targets]


def weighted_residuals(features: dict[str, float], targets: list[Target]) -> np.ndarray:
    """(len(targets),) ``(twin - target) / sigma``; a missing feature costs :data:`MISSING_PENALTY`."""
    out = []
    for t in targets:
        v = features.get(t.name, math.nan)
        out.append((v - t.value) / t.sigma if math.isfinite(v) else MISSING_PENALTY)
    return np.array(out)


def thesis_residual(cfg: TwinConfig, bench: str = BENCH_QUANTITY) -> float:
    """Sum of squared weighted residuals of the thesis targets (chi^2) for ``cfg``."""
    return float(np.sum(weighted_residuals(thesis_features(cfg, bench=bench), thesis_targets()) ** 2))


# ------------------------------------------------------------------------- a log of the robot
def read_log(path: Path) -> dict[str, dict[int, np.ndarray]]:
    """Group a log by command: {command: {wheel: (k, 2) t_s, rpm}}."""
    groups: dict[str, dict[int, list]] = {}
    with open(path, newline="") as fh:
        reader = csv.DictReader(fh)
        missing = {"t_s", "wheel", "rpm", "command"} - set(reader.fieldnames or [])
        if missing:
            raise ValueError(f"{path}: missing column(s) {sorted(missing)} (need t_s, wheel, rpm, command)")
        for line, row in enumerate(reader, 2):
            try:
                t, rpm = float(row["t_s"]), float(row["rpm"])
            except ValueError:
                raise ValueError(f"{path}:{line}: t_s and rpm must be numbers") from None
            wheel = {"0": 0, "left": 0, "1": 1, "right": 1}.get(row["wheel"].strip())
            if wheel is None or not (math.isfinite(t) and math.isfinite(rpm)):
                raise ValueError(f"{path}:{line}: wheel must be left/right/0/1 and values finite")
            Command.parse(row["command"], what=f"{path}:{line}: command")
            groups.setdefault(row["command"].strip(), {}).setdefault(wheel, []).append((t, rpm))
    if not groups:
        raise ValueError(f"{path}: no samples")
    return {cmd: {w: np.array(sorted(v)) for w, v in wheels.items()} for cmd, wheels in groups.items()}


def log_residuals(cfg: TwinConfig, log: dict[str, dict[int, np.ndarray]]) -> np.ndarray:
    """Twin minus log at the log's sample times, RPM (1 RPM per sample = 1 sigma)."""
    errors = []
    for text, wheels in log.items():
        duration = max(float(v[:, 0].max()) for v in wheels.values()) + 0.5
        series = run_command(cfg, Command.parse(text), duration, TwinOptions(world="empty")).series
        for w, samples in wheels.items():
            pub = series.published[w]
            if len(pub) < 2:
                errors.append(np.full(len(samples), MISSING_PENALTY))
                continue
            twin = np.interp(samples[:, 0], pub[:, 0], pub[:, 1], left=0.0)
            errors.append(twin - samples[:, 1])
    return np.concatenate(errors)


# ------------------------------------------------------------------------- the fit
def calibrate(target: str, base: TwinConfig | None = None, max_evaluations: int = 60,
              parameters: dict[str, tuple[float, float]] | None = None, progress=None, jobs: int = 1,
              bench: str = BENCH_QUANTITY) -> Fit:
    """Fit ``parameters`` (default :data:`PARAMETERS`) to ``target`` ("thesis" or a CSV path).

    ``base`` is the starting configuration (the parameter file with its overrides);
    ``jobs`` worker processes simulate a thesis evaluation's three runs in parallel.
    """
    from scipy.optimize import least_squares

    from amr_twin.experiments.executor import worker_pool

    base = base or load_config()
    parameters = parameters or PARAMETERS
    keys = list(parameters)
    lo, hi = np.array([parameters[k][0] for k in keys]), np.array([parameters[k][1] for k in keys])
    x0 = np.clip(np.array([_get(base, k) for k in keys]), lo, hi)
    log = read_log(Path(target)) if target != "thesis" else None
    targets = thesis_targets()
    count = [0]
    last: dict = {}
    pool = worker_pool(jobs) if jobs > 1 and log is None else None  # spawned, warm, die with this process

    def cfg_at(u: np.ndarray) -> TwinConfig:
        return _with(base, dict(zip(keys, (lo + (hi - lo) * u).tolist())))

    def f(u: np.ndarray) -> np.ndarray:
        count[0] += 1
        if progress is not None:
            progress(count[0], max_evaluations)
        cfg = cfg_at(u)
        if log is not None:
            return log_residuals(cfg, log)
        features = thesis_features(cfg, pool, bench)
        last[tuple(u)] = features
        return weighted_residuals(features, targets)

    try:
        # max_nfev counts the steps, not the finite differences: n + 1 evaluations per step
        res = least_squares(f, (x0 - lo) / (hi - lo), bounds=(0.0, 1.0), method="trf", diff_step=0.02,
                            max_nfev=max(2, max_evaluations // (len(keys) + 1)), x_scale=1.0)
        features = last.get(tuple(res.x)) if log is None else None
    finally:
        if pool is not None:
            pool.shutdown()
    values = lo + (hi - lo) * res.x
    sigma, corr = _uncertainty(res.jac, hi - lo)
    table = []
    if features is not None:
        for t, r in zip(targets, res.fun):
            table.append({"name": t.name, "twin": features.get(t.name), "target": t.value, "sigma": t.sigma,
                          "unit": t.unit, "weighted": float(r)})
    name = f"the thesis (bench point as {bench} current; ch. 5 runs 1-3)" if log is None else str(target)
    return Fit(values=dict(zip(keys, values.tolist())), sigma=dict(zip(keys, sigma.tolist())),
               correlation={a: dict(zip(keys, row.tolist())) for a, row in zip(keys, corr)},
               residual=float(np.sum(res.fun ** 2)), evaluations=count[0], target=name, features=table)


def _uncertainty(jac: np.ndarray, span: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """1-sigma uncertainties and correlations from the Jacobian of the weighted residuals.

    ``jac`` is taken in the scaled parameters (``x = lo + span u``); a parameter the
    targets do not determine gets an infinite uncertainty.
    """
    n = jac.shape[1]
    cov_u = np.linalg.pinv(jac.T @ jac)
    informed = np.abs(jac).sum(axis=0) > 0
    cov = cov_u * np.outer(span, span)
    sigma = np.sqrt(np.clip(np.diag(cov), 0.0, None))
    sigma[~informed] = math.inf
    with np.errstate(divide="ignore", invalid="ignore"):
        corr = cov / np.outer(sigma, sigma)
    corr[~np.isfinite(corr)] = 0.0
    corr[np.arange(n), np.arange(n)] = 1.0
    return sigma, np.clip(corr, -1.0, 1.0)


def _with(base: TwinConfig, values: dict[str, float]) -> TwinConfig:
    data = base.model_dump()
    for key, value in values.items():
        section, name = key.split(".")
        data[section][name] = value
    return TwinConfig.model_validate(data)


def _get(cfg: TwinConfig, key: str) -> float:
    section, name = key.split(".")
    return float(getattr(getattr(cfg, section), name))


def write_params(fit: Fit, path: Path) -> None:
    """Write the fitted values as an override file, atomically."""
    write_text(path, "# amr-twin calibration result: use with --params\n"
               + yaml.safe_dump(fit.override_tree(), sort_keys=False))
