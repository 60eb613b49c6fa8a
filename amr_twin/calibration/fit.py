"""Calibration: identify the drive's unknowns from measured data, with their uncertainty.

Unknowns (the thesis gives none of them): each driver board's gain (the ZS-X11D1 reads the
PWM as a speed demand), each motor's back-EMF constant ``Ke`` and its own dry
friction (bearings, seals, cogging). Every other drive parameter keeps its sourced
value (winding resistance, iron-loss damping, tyre and caster rolling resistance).
Two targets:

- ``thesis``: the bench point of listing 4.1 and chapter 5 runs 1-6, each feature against
  the thesis' value with its sigma;
- a log ``LOG.csv`` of real wheel speeds, compared sample by sample (1 RPM per sample).

The targets and the twin's value of each are in :mod:`amr_twin.calibration.targets`.

The fit is scipy's bounded ``least_squares`` (trust region reflective) in parameters
scaled to their bounds; its Jacobian at the optimum gives each parameter's standard
uncertainty and the correlations (``(J^T J)^-1``: the targets' sigmas are their
uncertainties). The result is an override file for ``--params``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import yaml

from amr_twin.base.atomic_file import write_text
from amr_twin.model.config import TwinConfig, load_config
from amr_twin.calibration.targets import (
    BENCH_QUANTITY,
    log_residuals,
    read_log,
    thesis_features,
    thesis_targets,
    weighted_residuals,
)

PARAMETERS = {  # dotted key: (lower, upper) bounds, physically plausible
    "driver_left.gain": (0.8, 4.0),
    "driver_right.gain": (0.8, 4.0),
    "motor_left.ke_v_s_rad": (0.35, 0.70),  # 36 V hub motors with 500-1000 RPM no load
    "motor_right.ke_v_s_rad": (0.35, 0.70),
    "motor_left.friction_nm": (0.0, 2.0),
    "motor_right.friction_nm": (0.0, 2.0),
}


@dataclass
class Fit:
    """Result of a calibration: values, 1-sigma uncertainties, correlations, residuals."""

    values: dict[str, float]
    sigma: dict[str, float]
    correlation: dict[str, dict[str, float]]
    residual: float  # sum of squared weighted residuals (chi^2)
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
                "value": round(float(value), 5),
                "unit": units[key],
                "source": f"calibrated: against {self.target}, 1 sigma {self.sigma[key]:.2g}, "
                f"residual "
                f"{self.residual:.3g} ({self.evaluations} evaluations, amr-twin calibrate)",
            }
        return tree

    def config(self, base: TwinConfig) -> TwinConfig:
        """``base`` with the fitted values."""
        return _with(base, self.values)

    def report(self) -> dict:
        """JSON-ready summary."""
        return {
            "target": self.target,
            "residual": self.residual,
            "evaluations": self.evaluations,
            "values": self.values,
            "sigma": self.sigma,
            "correlation": self.correlation,
            "features": self.features,
        }

    def text_lines(self, strong: float = 0.9) -> list[str]:
        """The summary a person reads (``amr-twin calibrate`` without ``--json``): chi^2, each value
        with its 1 sigma, the correlations above ``strong`` in magnitude, each feature against its
        target."""
        over = f" over {len(self.features)} targets" if self.features else ""
        lines = [
            f"calibrated against {self.target}: chi^2 {self.residual:.2f}{over}, "
            f"{self.evaluations} evaluations",
            "",
            f"{'parameter':28s} {'value':>10s} {'1 sigma':>10s}",
        ]
        lines += [
            f"{k:28s} {v:10.4g} {self.sigma.get(k, math.nan):10.2g}" for k, v in self.values.items()
        ]
        keys = list(self.values)
        pairs = [
            f"{a} ~ {b} {self.correlation[a][b]:+.2f}"
            for i, a in enumerate(keys)
            for b in keys[i + 1 :]
            if abs(self.correlation.get(a, {}).get(b, 0.0)) >= strong
        ]
        lines += [
            "",
            f"correlated (|r| >= {strong:g}):" + ("" if pairs else " none"),
            *(f"  {p}" for p in pairs),
        ]
        if self.features:
            lines += [
                "",
                f"{'feature':28s} {'twin':>10s} {'target':>10s} {'sigma':>8s} {'unit':5s} "
                f"{'(twin-target)/sigma':>20s}",
            ]
            lines += [
                f"{f['name']:28s} {_num(f['twin']):>10s} {f['target']:10.4g} {f['sigma']:8.3g} "
                f"{f['unit']:5s} "
                f"{_num(f['weighted'], '+.2f'):>20s}"
                for f in self.features
            ]
        return lines


def _num(value, spec: str = ".4g") -> str:
    """A feature's value; one the run does not show (None or NaN) as 'missing'."""
    return "missing" if value is None or not math.isfinite(value) else format(value, spec)


# ------------------------------------------------------------------------- the fit
def evaluations_per_step(parameters: dict[str, tuple[float, float]] | None = None) -> int:
    """Twin evaluations of one step of the fit: the point and one per parameter (its Jacobian)."""
    return len(parameters or PARAMETERS) + 1


def calibrate(
    target: str,
    base: TwinConfig | None = None,
    max_evaluations: int = 60,
    parameters: dict[str, tuple[float, float]] | None = None,
    progress=None,
    jobs: int = 1,
    bench: str = BENCH_QUANTITY,
) -> Fit:
    """Fit ``parameters`` (default :data:`PARAMETERS`) to ``target`` ("thesis" or a CSV path).

    ``base`` is the starting configuration (the parameter file with its overrides);
    ``jobs`` worker processes simulate a thesis evaluation's three runs in parallel. At most
    ``max_evaluations`` evaluations of the twin are made: scipy's ``max_nfev`` counts steps, each
    of which evaluates the point and, once accepted, its Jacobian (one more per parameter), so the
    fit takes ``max_evaluations // (parameters + 1)`` steps (ValueError below one step).
    """
    from scipy.optimize import least_squares

    from amr_twin.base.process_pool import worker_pool
    from amr_twin.recording.run import warm_up

    base = base or load_config()
    parameters = parameters or PARAMETERS
    keys = list(parameters)
    per_step = evaluations_per_step(parameters)
    if max_evaluations < per_step:
        raise ValueError(
            f"max_evaluations {max_evaluations}: at least {per_step} (the starting point and one "
            f"per "
            f"parameter for the Jacobian)"
        )
    lo, hi = np.array([parameters[k][0] for k in keys]), np.array([parameters[k][1] for k in keys])
    x0 = np.clip(np.array([_get(base, k) for k in keys]), lo, hi)
    log = read_log(Path(target)) if target != "thesis" else None
    targets = thesis_targets()
    count = [0]
    last: dict = {}
    pool = (
        worker_pool(jobs, warm_up) if jobs > 1 and log is None else None
    )  # spawned, warm, die with us

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
        # max_nfev counts the steps, not the finite differences: at most n + 1 evaluations per step
        res = least_squares(
            f,
            (x0 - lo) / (hi - lo),
            bounds=(0.0, 1.0),
            method="trf",
            diff_step=0.02,
            max_nfev=max_evaluations // per_step,
            x_scale=1.0,
        )
        features = last.get(tuple(res.x)) if log is None else None
    finally:
        if pool is not None:
            pool.shutdown()
    values = lo + (hi - lo) * res.x
    sigma, corr = _uncertainty(res.jac, hi - lo)
    table = []
    if features is not None:
        for t, r in zip(targets, res.fun):
            table.append(
                {
                    "name": t.name,
                    "twin": features.get(t.name),
                    "target": t.value,
                    "sigma": t.sigma,
                    "unit": t.unit,
                    "weighted": float(r),
                }
            )
    name = (
        f"the thesis (bench point as {bench} current; ch. 5 runs 1-6)"
        if log is None
        else str(target)
    )
    return Fit(
        values=dict(zip(keys, values.tolist())),
        sigma=dict(zip(keys, sigma.tolist())),
        correlation={a: dict(zip(keys, row.tolist())) for a, row in zip(keys, corr)},
        residual=float(np.sum(res.fun**2)),
        evaluations=count[0],
        target=name,
        features=table,
    )


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
    write_text(
        path,
        "# amr-twin calibration result: use with --params\n"
        + yaml.safe_dump(fit.override_tree(), sort_keys=False),
    )
