"""Monte Carlo over the parameters' uncertainty: drawn configurations and what moves the results.

Reasons and measurements: docs/how-to/uncertainty.md#amr_twincalibrationuncertainty."""

from __future__ import annotations

import hashlib
import json
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Sequence

import numpy as np

from amr_twin.model.config import ConfigError, TwinConfig, load_parameters
from amr_twin.model.parameter_tree import DEFAULT_CONFIG
from amr_twin.model.config_leaves import value_at
from amr_twin.model.parameter_spreads import (
    CALIBRATED,
    EXACT,
    FOLLOWS,
    NORMAL,
    UNIFORM,
    Spread,
    spread_of,
    with_values,
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
LEVEL = 0.90  # the reported interval: 5 % to 95 %


@dataclass(frozen=True)
class Draws:
    """Configurations drawn from a :class:`ParameterSpace`.

    ``names``: the drawn dimensions (``key`` or ``key[i]`` for a vector element), ``values``
    (n, d) their values; ``overrides[i]``: every parameter sample ``i`` changes (followers
    and shifted calibrated parameters included), ``{dotted key: value}``; ``clipped``: per
    name, how many draws were clipped to the bounds.
    """

    names: tuple[str, ...]
    values: np.ndarray
    overrides: tuple[dict, ...]
    seed: int
    sampler: str
    clipped: dict[str, int]

    def __len__(self) -> int:
        return len(self.overrides)

    def config(self, base: TwinConfig, i: int) -> TwinConfig:
        """``base`` with sample ``i``'s values (validated; one-line :class:`ConfigError`)."""
        return with_values(base, self.overrides[i])

    def sample_id(self, i: int) -> str:
        """10 hex digits naming sample ``i``'s values (part of a sweep's run keys)."""
        return hashlib.sha256(json.dumps(self.overrides[i], sort_keys=True).encode()).hexdigest()[
            :10
        ]

    def table(self) -> list[dict]:
        """One row per sample: ``sample``, ``id`` and each drawn dimension's value."""
        return [
            {"sample": i, "id": self.sample_id(i), **dict(zip(self.names, row.tolist()))}
            for i, row in enumerate(self.values)
        ]


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
                    f"give "
                    "the leaf a range or sigma"
                )
            fitted = float(self.calibration.values[self.calibration.keys.index(key)])
            if not math.isclose(fitted, s.value, rel_tol=1e-4, abs_tol=1e-9):
                raise ConfigError(
                    f"{key}: {s.value:g} here but {fitted:g} in the calibration report "
                    f"{self.calibration_path}: give the report of these values (--calibration "
                    f"FILE, "
                    "from amr-twin calibrate --report) or a range or sigma on the leaf"
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
            self._calibrated(
                values, block, norm.ppf(u[:, len(dims) - len(block) :]), x, len(dims) - len(block)
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

    def _calibrated(
        self, values: list[dict], block: list[str], z: np.ndarray, x: np.ndarray, col0: int
    ) -> None:
        """Fill the calibrated parameters of each sample: the fit's mean shifted by the held
        parameters' deviations, conditioned on members fixed by the user, plus ``L z``."""
        rep = self.calibration
        keys = list(rep.keys)
        held = [(j, k) for j, k in enumerate(rep.held_keys) if k in self.spreads]
        fixed = [
            i for i, k in enumerate(keys) if self.spreads.get(k) and self.spreads[k].kind == EXACT
        ]
        drawn = [keys.index(k) for k in block]
        shifted = [
            i
            for i, k in enumerate(keys)
            if self.spreads.get(k) and self.spreads[k].kind == CALIBRATED
        ]
        if not held and not drawn:
            return
        cov = rep.covariance
        gain = np.zeros((len(drawn), len(fixed)))
        cond = cov[np.ix_(drawn, drawn)]
        if fixed and drawn:
            inv = np.linalg.pinv(cov[np.ix_(fixed, fixed)])
            gain = cov[np.ix_(drawn, fixed)] @ inv
            cond = cond - gain @ cov[np.ix_(fixed, drawn)]
        lam, vec = (
            np.linalg.eigh(0.5 * (cond + cond.T)) if drawn else (np.zeros(0), np.zeros((0, 0)))
        )
        root = vec * np.sqrt(np.clip(lam, 0.0, None))
        for r, sample in enumerate(values):
            dev = np.array([self._value(sample, k) - rep.held_values[j] for j, k in held])
            mean = rep.values + (rep.follow[:, [j for j, _ in held]] @ dev if held else 0.0)
            out = mean.copy()
            if drawn:
                xf = np.array([self.spreads[keys[i]].value for i in fixed])
                out[drawn] = (
                    mean[drawn] + (gain @ (xf - mean[fixed]) if fixed else 0.0) + root @ z[r]
                )
            for i in shifted:
                sample[keys[i]] = float(out[i])
        for c, k in enumerate(block):
            x[:, col0 + c] = [v[k] for v in values]

    def _value(self, sample: dict, key: str) -> float:
        return float(sample[key]) if key in sample else float(self.spreads[key].value)


def interval(values: Sequence[float | None], level: float = LEVEL, discrete: bool = False) -> dict:
    """``{"median", "low", "high", "n"}``: the median and the ``level`` interval's quantiles of
    ``values`` (None and NaN left out; None for each when none is left).

    ``discrete``: quantiles that are values of the sample (numpy's ``inverted_cdf``), for
    answers on a grid or censored at ``±inf``, which are kept; otherwise linear
    interpolation between the finite values.
    """
    v = np.array([x for x in values if x is not None and not math.isnan(x)], dtype=float)
    if not discrete:
        v = v[np.isfinite(v)]
    if not len(v):
        return {"median": None, "low": None, "high": None, "n": 0}
    lo, med, hi = np.quantile(
        v, [(1 - level) / 2, 0.5, (1 + level) / 2], method="inverted_cdf" if discrete else "linear"
    )
    return {"median": float(med), "low": float(lo), "high": float(hi), "n": int(len(v))}


def rank_correlations(x: np.ndarray, y: Sequence[float | None]) -> np.ndarray:
    """(d,) Spearman rank correlation of each column of ``x`` (n, d) with ``y`` (n,), over the
    samples where ``y`` is a number (``±inf``, a censored answer, ranks last or first); NaN
    for a constant column or fewer than 3 samples."""
    from scipy.stats import rankdata

    y = np.array([np.nan if v is None else float(v) for v in y])
    ok = ~np.isnan(y)
    out = np.full(x.shape[1], np.nan)
    if ok.sum() < 3 or len(set(y[ok].tolist())) < 2:
        return out
    ry = rankdata(y[ok])
    ry = (ry - ry.mean()) / np.linalg.norm(ry - ry.mean())
    for j in range(x.shape[1]):
        rx = rankdata(x[ok, j])
        norm_x = np.linalg.norm(rx - rx.mean())
        if norm_x > 0:
            out[j] = float((rx - rx.mean()) @ ry / norm_x)
    return out


def noise_level(n: int, parameters: int = 1) -> float:
    """|rho| that the largest of ``parameters`` unrelated ones exceeds in ``n`` samples about one
    time in 20 (two-sided, Bonferroni: ``Phi^-1(1 - 0.025 / parameters) / sqrt(n - 1)``)."""
    from scipy.stats import norm

    return float(norm.ppf(1 - 0.025 / max(parameters, 1)) / math.sqrt(max(n - 1, 1)))
