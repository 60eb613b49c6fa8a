"""Monte Carlo over the parameters' uncertainty: drawn configurations and what moves the results.

Reasons and measurements: docs/how-to/uncertainty.md#amr_twincalibrationuncertainty."""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Sequence

import numpy as np

from amr_twin.calibration.draws import Draws
from amr_twin.calibration.joint_draw import draw_calibrated
from amr_twin.model.config import ConfigError, TwinConfig, load_parameters
from amr_twin.model.parameter_tree import DEFAULT_CONFIG
from amr_twin.model.config_leaves import value_at
from amr_twin.model.parameter_spreads import (
    CALIBRATED,
    FOLLOWS,
    NORMAL,
    UNIFORM,
    Spread,
    spread_of,
)

PLANT = (
    "sim.",
    "chassis.",
    "deck.",
    "components.",
    "wheel.",
    "caster.",
    "motor_left.",
    "motor_right.",
    "driver.",
    "driver_left.",
    "driver_right.",
    "battery.",
)
"""The robot's body and drive (not its sensors, nor the estimators)."""
SAMPLERS = ("lhs", "sobol")
MAX_SAMPLES = 4096


def _selected(key: str, include: Sequence[str]) -> bool:
    return any(key == p or (p.endswith(".") and key.startswith(p)) for p in include)


def unit_samples(n: int, d: int, seed: int, sampler: str = "lhs") -> np.ndarray:
    """(n, d) points in the open unit cube: Latin hypercube or scrambled Sobol (n a power of 2)."""
    from scipy.stats import qmc

    if sampler not in SAMPLERS:
        raise ValueError(f"sampler {sampler!r}: must be one of {', '.join(SAMPLERS)}")
    if not 1 <= n <= MAX_SAMPLES:
        raise ValueError(f"samples: {n} must be in 1..{MAX_SAMPLES}")
    if sampler == "sobol" and n & (n - 1):
        raise ValueError(f"samples: {n} with sobol must be a power of 2 (its balance needs it)")
    rng = np.random.default_rng(seed)
    engine = qmc.LatinHypercube if sampler == "lhs" else qmc.Sobol
    try:
        points = engine(d, rng=rng).random(n)
    except TypeError:  # scipy < 1.15 names it seed
        points = engine(d, seed=rng).random(n)
    return np.clip(points, 1e-12, 1 - 1e-12)


@dataclass(frozen=True)
class ParameterSpace:
    """Every parameter's :class:`~amr_twin.model.parameter_spreads.Spread` for one configuration."""

    cfg: TwinConfig
    spreads: dict[str, Spread]
    calibration: Any = None  # amr_twin.calibration.report.CalibrationReport or None
    calibration_path: Path | None = None

    @classmethod
    def load(
        cls,
        path: str | Path | None = None,
        *,
        override_file: str | Path | None = None,
        sets: Sequence[str] = (),
        overrides: dict | None = None,
        calibration: str | Path | None = None,
    ) -> "ParameterSpace":
        """The parameter file with its overrides (as :func:`amr_twin.model.config.load_config`) and
        the calibration's report (default ``calibration.yaml`` beside the parameter file)."""
        from amr_twin.calibration import report as calibration_report

        cfg, meta = load_parameters(
            path, override_file=override_file, sets=sets, overrides=overrides
        )
        report_path = (
            Path(calibration)
            if calibration is not None
            else Path(path or DEFAULT_CONFIG).parent / "calibration.yaml"
        )
        report = (
            calibration_report.read(report_path)
            if calibration is not None or report_path.exists()
            else None
        )
        tree = cfg.model_dump()
        sigma = dict(zip(report.keys, report.sigma.tolist())) if report is not None else None
        spreads = {}
        for key, m in meta.items():
            value = value_at(tree, key)
            spreads[key] = spread_of(
                key, list(value) if isinstance(value, tuple) else value, m, sigma
            )
        space = cls(cfg, spreads, report, report_path if report is not None else None)
        space._check_calibration()
        return space

    def _check_calibration(self) -> None:
        for key, s in self.spreads.items():
            if s.kind != CALIBRATED:
                continue
            if s.sigma is None:
                where = (
                    f"the calibration report {self.calibration_path} does not cover it"
                    if self.calibration_path
                    else "no calibration report (calibration.yaml beside the parameter file, or "
                    "--calibration)"
                )
                raise ConfigError(
                    f"{key}: calibrated, but {where}: amr-twin calibrate --report writes one; or "
                    f"give the leaf a range or sigma"
                )
            fitted = float(self.calibration.values[self.calibration.keys.index(key)])
            if not math.isclose(fitted, s.value, rel_tol=1e-4, abs_tol=1e-9):
                raise ConfigError(
                    f"{key}: {s.value:g} here but {fitted:g} in the calibration report "
                    f"{self.calibration_path}: give the report of these values (--calibration "
                    f"FILE, from amr-twin calibrate --report) or a range or sigma on the leaf"
                )

    def drawn_keys(self, include: Sequence[str] = PLANT) -> list[str]:
        """The parameters :meth:`draw` varies for ``include``, in file order."""
        chosen = {
            k
            for k, s in self.spreads.items()
            if s.drawn and s.kind != FOLLOWS and _selected(k, include)
        }
        if any(self.spreads[k].kind == CALIBRATED for k in chosen):  # one fit: drawn whole
            chosen |= {k for k, s in self.spreads.items() if s.kind == CALIBRATED}
        chosen |= {k for k, s in self.spreads.items() if s.kind == FOLLOWS and s.follows in chosen}
        return [k for k in self.spreads if k in chosen]

    def draw(
        self, n: int, seed: int = 0, include: Sequence[str] = PLANT, sampler: str = "lhs"
    ) -> Draws:
        """``n`` configurations (see the module notes); raises ValueError or ConfigError naming the
        problem."""
        from scipy.stats import norm

        keys = self.drawn_keys(include)
        free = [k for k in keys if self.spreads[k].kind in (UNIFORM, NORMAL)]
        block = [k for k in keys if self.spreads[k].kind == CALIBRATED]
        dims = [
            (k, i)
            for k in free
            for i in range(len(self.spreads[k].sigma or (0,)))
            if self.spreads[k].kind == UNIFORM or self.spreads[k].sigma[i] > 0
        ] + [(k, 0) for k in block]
        if not dims:
            raise ValueError(
                f"nothing to draw: no parameter with a spread matches {', '.join(include)}"
            )
        u = unit_samples(n, len(dims), seed, sampler)
        x = np.empty_like(u)
        for j, (key, i) in enumerate(dims):
            s = self.spreads[key]
            if s.kind == UNIFORM:
                x[:, j] = s.low + (s.high - s.low) * u[:, j]
            elif s.kind == NORMAL:
                centre = s.value[i] if isinstance(s.value, list) else s.value
                x[:, j] = centre + s.sigma[i] * norm.ppf(u[:, j])
        values = [
            {
                key: (
                    list(self.spreads[key].value)
                    if isinstance(self.spreads[key].value, list)
                    else self.spreads[key].value
                )
                for key in free
            }
            for _ in range(n)
        ]
        for j, (key, i) in enumerate(dims[: len(dims) - len(block)]):
            for r in range(n):
                if isinstance(values[r][key], list):
                    values[r][key][i] = float(x[r, j])
                else:
                    values[r][key] = float(x[r, j])
        self._follow(values, keys)  # held parameters' followers first: the fit follows them too
        if self.calibration is not None:
            draw_calibrated(
                self.calibration,
                self.spreads,
                values,
                block,
                norm.ppf(u[:, len(dims) - len(block) :]),
                x,
                len(dims) - len(block),
            )
            self._follow(values, keys)
        clipped = {}
        for r in range(n):
            for key, v in values[r].items():
                lo, hi = self._bounds(key)
                items = v if isinstance(v, list) else [v]
                out = [min(max(e, lo), hi) for e in items]
                for e, o, idx in zip(items, out, range(len(items))):
                    if e != o:
                        name = f"{key}[{idx}]" if isinstance(v, list) else key
                        clipped[name] = clipped.get(name, 0) + 1
                out = [float(f"{e:.6g}") for e in out]
                values[r][key] = out if isinstance(v, list) else out[0]
        names = tuple(
            f"{k}[{i}]" if isinstance(self.spreads[k].value, list) else k for k, i in dims
        )
        table = np.array(
            [
                [
                    values[r][k][i] if isinstance(values[r][k], list) else values[r][k]
                    for k, i in dims
                ]
                for r in range(n)
            ]
        )
        draws = Draws(names, table, tuple(values), seed, sampler, clipped)
        for r in range(n):
            try:
                draws.config(self.cfg, r)
            except ConfigError as exc:
                raise ConfigError(
                    f"sample {r} of seed {seed}: {exc} (narrow a range in the parameter file)"
                ) from None
        return draws

    def _follow(self, values: list[dict], keys: list[str]) -> None:
        for key in keys:
            s = self.spreads[key]
            if s.kind == FOLLOWS:
                lead = self.spreads[s.follows].value
                for sample in values:
                    sample[key] = s.value * self._value(sample, s.follows) / lead

    def _bounds(self, key: str) -> tuple[float, float]:
        lo, hi = self.spreads[key].bounds
        if self.calibration is not None and key in self.calibration.keys:
            b = self.calibration.bounds[self.calibration.keys.index(key)]
            lo, hi = max(lo, b[0]), min(hi, b[1])
        return lo, hi

    def _value(self, sample: dict, key: str) -> float:
        return float(sample[key]) if key in sample else float(self.spreads[key].value)
