"""Calibration: fit the plant's unknowns so the twin reproduces measured wheel speeds.

Unknowns (the thesis gives none of them): the driver's gain (the ZS-X11D1 reads the
PWM as a speed demand), each motor's back-EMF constant and its drag torque (the
left/right difference of §5.1.3). Two targets:

- ``thesis``: the chapter 5 single-wheel and linear runs, judged on the published
  samples of the faithful firmware: the steady speed tracks the reference (the
  thesis' "almost perfect track"), the right wheel overshoots by about 4 RPM and
  the left by about 1.5 RPM (§5.1.3).
- a log ``LOG.csv`` of real wheel speeds (columns ``t_s, wheel, rpm, command``;
  ``command`` as in ``amr-twin sweep``: ``linear:0.7``, ``angular:-60:-1``,
  ``motor:left:1.0`` or ``motor:left:forward:1.0``): each command's run is simulated for the log's
  duration and the published speeds are compared with the log at the log's times.

The fit is a bounded Nelder-Mead search (scipy) on a few parameters; each
evaluation runs the twin. The result is an override file for ``--params``.
"""

from __future__ import annotations

import csv
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import yaml
from scipy.optimize import minimize

from .atomic_file import write_text
from .config import TwinConfig, load_config
from .loop import TwinOptions
from .metrics import step_info
from .run import Command, run_command

PARAMETERS = {  # dotted key: (lower, upper) bounds, physically plausible
    "driver.gain": (1.0, 3.0),
    "motor_left.ke_v_s_rad": (0.35, 0.70),
    "motor_right.ke_v_s_rad": (0.35, 0.70),
    "motor_left.friction_nm": (0.0, 0.8),
    "motor_right.friction_nm": (0.0, 0.8),
}
THESIS_RUNS = [  # (command, duration_s, wheels judged)
    (Command("motor", wheel="left", speed_m_s=1.0), 10.0, (0,)),
    (Command("motor", wheel="right", speed_m_s=1.0), 10.0, (1,)),
    (Command("linear", speed_m_s=0.7), 10.0, (0, 1)),
]
THESIS_OVERSHOOT_RPM = {0: 1.5, 1: 4.0}  # §5.1.3: left 0-2 RPM, right about 4 RPM


@dataclass
class Fit:
    """Result of a calibration."""

    values: dict[str, float]
    residual: float
    evaluations: int
    target: str

    def override_tree(self) -> dict:
        """Nested YAML tree for ``--params`` (values with unit and source)."""
        from .config import parameter_table

        units = {key: unit for key, _v, unit, _s in parameter_table()}
        tree: dict = {}
        for key, value in self.values.items():
            section, name = key.split(".")
            tree.setdefault(section, {})[name] = {
                "value": round(float(value), 5), "unit": units[key],
                "source": f"calibrated: against {self.target}, residual {self.residual:.3g} "
                          f"({self.evaluations} evaluations, amr-twin calibrate)"}
        return tree


def parse_command(text: str) -> Command:
    """A log's ``command`` column -> Command (see :meth:`Command.parse`)."""
    return Command.parse(text)


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
            groups.setdefault(row["command"].strip(), {}).setdefault(wheel, []).append((t, rpm))
    return {cmd: {w: np.array(sorted(v)) for w, v in wheels.items()} for cmd, wheels in groups.items()}


def _cfg_with(base_sets: list[str], values: dict[str, float]) -> TwinConfig:
    return load_config(sets=base_sets, overrides=values)


def thesis_residual(cfg: TwinConfig) -> float:
    """Weighted squared error of the chapter 5 features (RPM^2)."""
    total = 0.0
    for command, duration_s, wheels in THESIS_RUNS:
        series = run_command(cfg, command, duration_s, TwinOptions(world="empty")).series
        for w in wheels:
            samples = series.published[w]
            ref = abs(command_reference(cfg, command)[w])
            if len(samples) < 3:
                return 1e6
            info = step_info(samples[:, 0], samples[:, 1], ref)
            late = samples[samples[:, 0] > 0.5 * duration_s, 1]
            total += (late.mean() - ref) ** 2 + (info.overshoot - THESIS_OVERSHOOT_RPM[w]) ** 2
    return total


def command_reference(cfg: TwinConfig, command: Command) -> tuple[float, float]:
    """Signed wheel references (RPM) the client sends for ``command``."""
    from .bus import Bus
    from .clock import VirtualClock
    from .controllers.wheel_command import WheelCommandClient, WheelCommandService

    bus = Bus(VirtualClock())
    WheelCommandService(bus)
    client = WheelCommandClient(bus, wheel_radius_m=cfg.wheel.radius_m, half_separation_m=cfg.wheel.separation_m / 2)
    command.send(type("T", (), {"client": client})())
    r = client.last_request
    return (r.motionL * r.speedL, r.motionR * r.speedR) if r is not None else (0.0, 0.0)


def log_residual(cfg: TwinConfig, log: dict[str, dict[int, np.ndarray]]) -> float:
    """Mean squared difference between the log and the twin's published speeds (RPM^2)."""
    errors = []
    for text, wheels in log.items():
        duration = max(float(v[:, 0].max()) for v in wheels.values()) + 0.5
        series = run_command(cfg, parse_command(text), duration, TwinOptions(world="empty")).series
        for w, samples in wheels.items():
            pub = series.published[w]
            if len(pub) < 2:
                errors.append(np.full(len(samples), 1e3))
                continue
            twin = np.interp(samples[:, 0], pub[:, 0], pub[:, 1], left=0.0)
            errors.append(twin - samples[:, 1])
    return float(np.mean(np.concatenate(errors) ** 2))


def calibrate(target: str, base_sets: list[str] | None = None, max_evaluations: int = 40,
              parameters: dict[str, tuple[float, float]] | None = None, progress=None) -> Fit:
    """Fit ``parameters`` (default :data:`PARAMETERS`) to ``target`` ("thesis" or a CSV path)."""
    base_sets = list(base_sets or [])
    parameters = parameters or PARAMETERS
    keys = list(parameters)
    base = load_config(sets=base_sets)
    x0 = np.array([_get(base, k) for k in keys])
    lo, hi = np.array([parameters[k][0] for k in keys]), np.array([parameters[k][1] for k in keys])
    if target == "thesis":
        objective = thesis_residual
    else:
        log = read_log(Path(target))
        objective = lambda cfg: log_residual(cfg, log)  # noqa: E731
    count = [0]

    def f(z: np.ndarray) -> float:
        x = lo + (hi - lo) * (np.sin(z) + 1) / 2  # bounded by construction
        count[0] += 1
        if progress is not None:
            progress(count[0], max_evaluations)
        return objective(_cfg_with(base_sets, dict(zip(keys, x.tolist()))))

    z0 = np.arcsin(np.clip(2 * (x0 - lo) / (hi - lo) - 1, -1, 1))
    res = minimize(f, z0, method="Nelder-Mead",
                   options={"maxfev": max_evaluations, "xatol": 1e-3, "fatol": 1e-3,
                            "initial_simplex": _simplex(z0, 0.15)})
    x = lo + (hi - lo) * (np.sin(res.x) + 1) / 2
    return Fit(values=dict(zip(keys, x.tolist())), residual=float(res.fun), evaluations=count[0],
               target="thesis ch. 5 (published samples)" if target == "thesis" else str(target))


def _simplex(z0: np.ndarray, step: float) -> np.ndarray:
    return np.vstack([z0] + [z0 + step * np.eye(len(z0))[i] for i in range(len(z0))])


def _get(cfg: TwinConfig, key: str) -> float:
    section, name = key.split(".")
    return float(getattr(getattr(cfg, section), name))


def write_params(fit: Fit, path: Path) -> None:
    """Write the fitted values as an override file, atomically."""
    write_text(path, "# amr-twin calibration result: use with --params\n"
               + yaml.safe_dump(fit.override_tree(), sort_keys=False))
