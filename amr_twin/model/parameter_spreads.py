"""How uncertain each parameter is: one :class:`Spread` per leaf of the parameter file.

Each is one of:

- ``range: [lo, hi]`` on the leaf: uniform on ``[lo, hi]``; ``sigma: s``: normal about
  the value (one sigma per element for a vector; ``sigma: 0`` holds it exact);
  ``follows: other.key``: the same relative deviation as that parameter (two parts
  of one model, such as both motors' winding resistance);
- otherwise by the source's kind (:data:`DEFAULT_TOLERANCE`): a figure of the thesis
  ±2 %, a datasheet's ±5 %, an estimate ±20 % (uniform; a vector, a zero or an
  integer stays exact unless its leaf says otherwise); **calibrated**: from
  the calibration's report (:mod:`amr_twin.calibration.report`,
  ``models/amr/calibration.yaml`` beside the parameter file): drawn *jointly* from
  its normal (driver gain and both ``Ke`` correlate at 0.99: drawn independently they
  would make plants the thesis rules out), each draw shifted by how the fit follows
  the parameters it held (winding resistance, damping, rolling resistance, the
  battery), so that every draw is still a fit;
- exact: settings (``P(..., setting=True)``: time step, payload, sensor modes,
  estimator tuning), other kinds (standard gravity), and values replaced by
  ``--set`` or a plain ``--params`` value (the user chose them; a calibrated
  parameter set so conditions the others of its fit on it).

The draws themselves are :mod:`amr_twin.calibration.uncertainty`'s.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from amr_twin.model.config import ConfigError, TwinConfig
from amr_twin.model.config_leaves import field_range

DEFAULT_TOLERANCE = {"thesis": 0.02, "datasheet": 0.05, "estimate": 0.20}
"""Half-width of the default uniform spread, relative to the value, by source kind."""
UNIFORM, NORMAL, CALIBRATED, FOLLOWS, EXACT = "uniform", "normal", "calibrated", "follows", "exact"


def source_kind(source: str) -> str:
    """``calibrated``, ``datasheet``, ``thesis``, ``estimate`` or ``other`` from a leaf's source."""
    text = source.strip().lower()
    for kind in ("calibrated", "datasheet", "thesis", "estimate"):
        if text.startswith(kind):
            return kind
    return "estimate" if "decision" in text.split(":")[0] else "other"  # robot-facts.md decisions


@dataclass(frozen=True)
class Spread:
    """The uncertainty of one parameter (see the module notes); values in its own unit."""

    key: str
    kind: str
    value: Any
    reason: str
    low: float | None = None
    high: float | None = None
    sigma: tuple[float, ...] | None = None
    follows: str | None = None
    bounds: tuple[float, float] = (-math.inf, math.inf)

    @property
    def drawn(self) -> bool:
        return self.kind in (UNIFORM, CALIBRATED, FOLLOWS) or (
            self.kind == NORMAL and any(self.sigma)
        )

    def describe(self) -> str:
        """Short text for tables: ``[lo, hi]``, ``σ s``, ``follows k`` or ``exact``."""
        if self.kind == UNIFORM:
            return f"[{self.low:.4g}, {self.high:.4g}]"
        if self.kind in (NORMAL, CALIBRATED) and self.drawn:
            return "σ " + ", ".join(f"{s:.3g}" for s in self.sigma)
        return f"follows `{self.follows}`" if self.kind == FOLLOWS else "exact"


def schema_bounds(key: str) -> tuple[float, float]:
    section, name = key.rsplit(".", 1)
    model: Any = TwinConfig
    for part in section.split("."):
        model = model.model_fields[part].annotation
    lo, hi, _ = field_range(model, [name])
    field = model.model_fields[name]
    lo = -math.inf if lo == "-inf" else float(lo)
    hi = math.inf if hi == "inf" else float(hi)
    strict = {type(m).__name__ for m in field.metadata}
    if "Gt" in strict:
        lo = float(np.nextafter(lo, math.inf))
    if "Lt" in strict:
        hi = float(np.nextafter(hi, -math.inf))
    return lo, hi


def _is_setting(key: str) -> bool:
    section, name = key.rsplit(".", 1)
    model: Any = TwinConfig
    for part in section.split("."):
        model = model.model_fields[part].annotation
    extra = model.model_fields[name].json_schema_extra
    return bool(model.SETTINGS or (isinstance(extra, dict) and extra.get("setting")))


def spread_of(
    key: str, value: Any, meta: dict, calibrated: dict[str, float] | None = None
) -> Spread:
    """A parameter's :class:`Spread` from its leaf description (``meta`` of
    :func:`amr_twin.model.config.load_parameters`). ``calibrated``: 1 sigma of the calibration's
    parameters (their correlations are the report's)."""
    bounds = schema_bounds(key)
    if _is_setting(key):
        return Spread(key, EXACT, value, "a setting, not a property of the robot")
    if "range" in meta:
        return Spread(key, UNIFORM, value, meta["reason"], *meta["range"], bounds=bounds)
    if "sigma" in meta:
        sigma = tuple(meta["sigma"]) if isinstance(meta["sigma"], list) else (float(meta["sigma"]),)
        return Spread(key, NORMAL, value, meta["reason"], sigma=sigma, bounds=bounds)
    if "follows" in meta:
        return Spread(key, FOLLOWS, value, meta["reason"], follows=meta["follows"], bounds=bounds)
    if "set_by" in meta:
        return Spread(key, EXACT, value, f"set by {meta['set_by']}")
    kind = source_kind(meta["source"])
    if kind == "calibrated":
        if calibrated is None or key not in calibrated:
            return Spread(
                key,
                CALIBRATED,
                value,
                "calibrated: no calibration report covers it",
                sigma=None,
                bounds=bounds,
            )
        return Spread(
            key,
            CALIBRATED,
            value,
            "the calibration's report (joint normal)",
            sigma=(calibrated[key],),
            bounds=bounds,
        )
    if kind not in DEFAULT_TOLERANCE:
        return Spread(key, EXACT, value, f"exact ({meta['source'].split(':')[0]})")
    if isinstance(value, bool) or not isinstance(value, float) or value == 0.0:
        what = (
            "a vector" if isinstance(value, list) else "zero" if value == 0 else "not a real number"
        )
        return Spread(key, EXACT, value, f"{kind} default: {what}, no relative tolerance")
    tol = DEFAULT_TOLERANCE[kind]
    lo, hi = sorted((value * (1 - tol), value * (1 + tol)))
    lo, hi = max(lo, bounds[0]), min(hi, bounds[1])
    return Spread(key, UNIFORM, value, f"{kind} default ±{tol:.0%}", lo, hi, bounds=bounds)


def with_values(base: TwinConfig, values: dict[str, Any]) -> TwinConfig:
    """``base`` with ``{dotted key: value}`` replaced, validated again."""
    from pydantic import ValidationError

    from amr_twin.model.config_errors import validation_message

    data = base.model_dump()
    for key, value in values.items():
        node = data
        *path, name = key.split(".")
        for part in path:
            node = node[part]
        node[name] = value
    try:
        return TwinConfig.model_validate(data)
    except ValidationError as exc:
        raise ConfigError(validation_message(exc, TwinConfig)) from None
