"""The calibration's report: the fitted values, their 1-sigma uncertainty and correlations,
and how the fit would follow the parameters it held at their sourced values.

Reasons and measurements: docs/explanation/validation.md#amr_twincalibrationreport."""

from __future__ import annotations

from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

import numpy as np
import yaml

from amr_twin.model.config import ConfigError, TwinConfig

# held parameter: forward step of its derivative (a fair part of its spread, above the features'
# noise)
HELD = {
    "motor_left.resistance_ohm": 0.03,
    "motor_right.resistance_ohm": 0.03,
    "motor_left.damping_nm_s_rad": 0.004,
    "motor_right.damping_nm_s_rad": 0.004,
    "wheel.rolling_resistance": 0.003,
    "caster.rolling_resistance": 0.005,
    "wheel.mass_kg": 0.3,
    "wheel.rotor_fraction": 0.06,
    "battery.soc_initial": 0.1,
    "battery.v_nominal_v": 0.7,
    "battery.v_full_v": 0.8,
    "battery.internal_resistance_ohm": 0.03,
}
"""Not held: ``wheel.radius_m``. Its derivative is lost in the 8-bit duty's steps (the radius sets
the commanded RPM): steps of 1 and 2 mm gave the driver gain -68 and +4.7 per metre."""
STEP_FRACTION = (
    0.02  # the fit's finite-difference step, in its scaled variables (amr_twin.calibration.fit)
)


@dataclass(frozen=True)
class CalibrationReport:
    """A calibration's linearised result (see the module notes). Units: each parameter's own."""

    target: str
    chi2: float
    keys: tuple[str, ...]  # fitted parameters, in the fit's order
    values: np.ndarray  # (k,)
    sigma: np.ndarray  # (k,) 1 sigma
    correlation: np.ndarray  # (k, k)
    bounds: np.ndarray  # (k, 2) the fit's bounds
    held_keys: tuple[str, ...]  # parameters held at their sourced values
    held_values: np.ndarray  # (h,) at which the fit was made
    follow: np.ndarray  # (k, h) d fitted / d held
    undetermined: tuple[
        str, ...
    ] = ()  # fitted parameters whose 1 sigma would exceed their bounds (left out)

    @property
    def covariance(self) -> np.ndarray:
        """(k, k) covariance of the fitted parameters."""
        return self.correlation * np.outer(self.sigma, self.sigma)

    def as_fit(self, fit=None):
        """An :class:`amr_twin.calibration.fit.Fit` with this report's uncertainty: ``fit``'s values
        and residuals when given (a fit this report was evaluated at), else the report's."""
        import dataclasses

        from amr_twin.calibration.fit import Fit

        sigma = dict(zip(self.keys, self.sigma.tolist()))
        corr = {
            a: dict(zip(self.keys, row.tolist())) for a, row in zip(self.keys, self.correlation)
        }
        if (
            fit is not None
        ):  # parameters the report leaves out (undetermined) keep the fit's own figures
            return dataclasses.replace(
                fit,
                sigma={**fit.sigma, **sigma},
                correlation={
                    k: {**fit.correlation.get(k, {}), **corr.get(k, {})} for k in fit.correlation
                },
            )
        return Fit(
            values=dict(zip(self.keys, self.values.tolist())),
            sigma=sigma,
            correlation=corr,
            residual=self.chi2,
            evaluations=1 + len(self.keys) + len(self.held_keys),
            target=self.target,
        )

    def as_dict(self) -> dict:
        """The YAML tree of the report."""
        r = lambda v: float(f"{float(v):.6g}")  # noqa: E731
        return {
            "target": self.target,
            "chi2": r(self.chi2),
            "parameters": {
                k: {"value": r(v), "sigma": r(s), "bounds": [r(b) for b in bd]}
                for k, v, s, bd in zip(self.keys, self.values, self.sigma, self.bounds)
            },
            "correlation": [[r(c) for c in row] for row in self.correlation],
            "held": {
                k: {"value": r(v), "follow": {f: r(d) for f, d in zip(self.keys, col)}}
                for k, v, col in zip(self.held_keys, self.held_values, self.follow.T)
            },
            **({"undetermined": list(self.undetermined)} if self.undetermined else {}),
        }

    @classmethod
    def from_dict(cls, tree: dict, where: str = "calibration report") -> "CalibrationReport":
        try:
            params = tree["parameters"]
            keys = tuple(params)
            held = tree.get("held") or {}
            report = cls(
                target=str(tree["target"]),
                chi2=float(tree["chi2"]),
                keys=keys,
                values=np.array([float(params[k]["value"]) for k in keys]),
                sigma=np.array([float(params[k]["sigma"]) for k in keys]),
                correlation=np.array(tree["correlation"], dtype=float),
                bounds=np.array([params[k]["bounds"] for k in keys], dtype=float).reshape(
                    len(keys), 2
                ),
                held_keys=tuple(held),
                held_values=np.array([float(h["value"]) for h in held.values()]),
                follow=np.array(
                    [[float(h["follow"][k]) for h in held.values()] for k in keys]
                ).reshape(len(keys), len(held)),
                undetermined=tuple(tree.get("undetermined") or ()),
            )
        except (KeyError, TypeError, ValueError) as exc:
            why = (
                f"no {exc.args[0]!r} key" if isinstance(exc, KeyError) else str(exc).splitlines()[0]
            )
            raise ConfigError(
                f"{where}: not a calibration report ({why}); amr-twin calibrate --report writes one"
            ) from None
        if report.correlation.shape != (len(keys), len(keys)) or not np.all(
            np.isfinite(report.sigma)
        ):
            raise ConfigError(
                f"{where}: the correlation must be {len(keys)} x {len(keys)} and every sigma finite"
            )
        return report


def read(path: str | Path) -> CalibrationReport:
    """Read a report file (one-line :class:`ConfigError` if it is missing or malformed)."""
    from amr_twin.model.yaml_file import read_yaml

    path = Path(path)
    if not path.exists():
        raise ConfigError(f"{path}: no such calibration report")
    tree = read_yaml(
        path, "calibration report", ConfigError
    )  # a device, a pipe, binary or bad YAML: one line
    return CalibrationReport.from_dict(tree if isinstance(tree, dict) else {}, str(path))


def write(report: CalibrationReport, path: str | Path) -> None:
    """Write a report atomically."""
    from amr_twin.base.atomic_file import write_text

    write_text(
        Path(path),
        "# amr-twin calibration report (amr-twin calibrate --report): the fitted values, their\n"
        "# 1 sigma and correlations, and d fitted / d held for the parameters the fit held fixed\n"
        + yaml.safe_dump(report.as_dict(), sort_keys=False, width=120, default_flow_style=None),
    )


def _residual_function(target: str, pool) -> Callable[[TwinConfig], np.ndarray]:
    from amr_twin.calibration import targets as ct

    if target == "thesis":
        targets = ct.thesis_targets()
        return lambda cfg: ct.weighted_residuals(ct.thesis_features(cfg, pool), targets)
    log = ct.read_log(Path(target))
    return lambda cfg: ct.log_residuals(cfg, log)


def evaluate(
    cfg: TwinConfig,
    target: str = "thesis",
    parameters: dict[str, tuple[float, float]] | None = None,
    held: dict[str, float] | None = None,
    jobs: int = 1,
    progress=None,
) -> CalibrationReport:
    """Linearise the calibration at ``cfg`` (see the module notes): ``1 + k + h`` evaluations.

    A fitted parameter the targets cannot place within its bounds (1 sigma above the bounds'
    span: the right motor in a log of the left wheel) is left out of the report, listed in
    ``undetermined``; the others' uncertainty is then given with it held.

    Parameters
    ----------
    cfg : the configuration whose fitted values are reported (a fit's result, or the shipped file).
    target : "thesis" or the path of a log (as :func:`amr_twin.calibration.fit.calibrate`).
    parameters : fitted parameters and their bounds (default
    :data:`amr_twin.calibration.fit.PARAMETERS`). held : held parameters and their forward steps
    (default :data:`HELD`). jobs : worker processes for a thesis evaluation's three runs.
    progress : ``progress(i, n)`` after each evaluation.
    """
    from amr_twin.calibration import fit as cal

    parameters = parameters or cal.PARAMETERS
    held = dict(HELD if held is None else held)
    for key in held:
        if key in parameters:
            raise ValueError(f"{key}: both fitted and held")
    keys, held_keys = list(parameters), list(held)
    lo, hi = np.array([parameters[k][0] for k in keys]), np.array([parameters[k][1] for k in keys])
    span = hi - lo
    x0 = np.array([cal._get(cfg, k) for k in keys])
    b0 = np.array([cal._get(cfg, k) for k in held_keys])
    total = 1 + len(keys) + len(held_keys)
    pool = ProcessPoolExecutor(jobs) if jobs > 1 and target == "thesis" else None
    try:
        f = _residual_function(target, pool)
        count = [0]

        def at(values: dict[str, float]) -> np.ndarray:
            out = f(cal._with(cfg, values))
            count[0] += 1
            if progress is not None:
                progress(count[0], total)
            return out

        r0 = at({})
        jac_u = np.zeros((len(r0), len(keys)))
        for j, key in enumerate(keys):
            u = (x0[j] - lo[j]) / span[j]
            h = STEP_FRACTION if u + STEP_FRACTION <= 1.0 else -STEP_FRACTION
            jac_u[:, j] = (at({key: float(x0[j] + h * span[j])}) - r0) / h
        jac_b = np.zeros((len(r0), len(held_keys)))
        for j, key in enumerate(held_keys):
            jac_b[:, j] = (at({key: float(b0[j] + held[key])}) - r0) / held[key]
    finally:
        if pool is not None:
            pool.shutdown()
    sigma_all, _ = cal._uncertainty(jac_u, span)
    keep = (
        sigma_all <= span
    )  # the targets place it within its bounds (not so: the right motor in a left-wheel log)
    undetermined = tuple(k for k, ok in zip(keys, keep) if not ok)
    keys, jac_u, span, x0, lo, hi = (
        [k for k, ok in zip(keys, keep) if ok],
        jac_u[:, keep],
        span[keep],
        x0[keep],
        lo[keep],
        hi[keep],
    )
    if not keys:
        raise ValueError("the targets determine none of the fitted parameters")
    sigma, corr = cal._uncertainty(jac_u, span)
    jac_a = jac_u / span  # d r / d x in the parameters' own units
    follow = -np.linalg.pinv(jac_a.T @ jac_a) @ jac_a.T @ jac_b
    name = (
        "the thesis (bench point as motor current; ch. 5 runs 1-6)"
        if target == "thesis"
        else str(target)
    )
    return CalibrationReport(
        target=name,
        chi2=float(np.sum(r0**2)),
        keys=tuple(keys),
        values=x0,
        sigma=sigma,
        correlation=corr,
        bounds=np.column_stack([lo, hi]),
        held_keys=tuple(held_keys),
        held_values=b0,
        follow=follow,
        undetermined=undetermined,
    )
