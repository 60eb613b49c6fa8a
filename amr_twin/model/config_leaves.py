"""The keys of a parameter leaf beyond its value: unit, source, and its uncertainty.

:mod:`amr_twin.model.config` reads each leaf ``{value, unit, source}`` of the parameter file;
a leaf may add one of ``range: [lo, hi]``, ``sigma: s`` or ``follows: section.key``
with a ``reason:`` (see :mod:`amr_twin.calibration.uncertainty` for what they mean when drawing).
This module checks them, one line per refusal naming the parameter.
"""

from __future__ import annotations

import math
from typing import Any

from pydantic import BaseModel

LEAF_KEYS = ("value", "unit", "source", "range", "sigma", "follows", "reason")
SPREAD_KEYS = ("range", "sigma", "follows")


class ConfigError(ValueError):
    """A parameter file or override is invalid; the message is one line (re-exported by config)."""


def _error(message: str) -> Exception:
    return ConfigError(message)


def is_number(v: Any) -> bool:
    """A finite int or float (not a bool)."""
    return isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)


def leaf_spread(sub: dict, path: str, model: type[BaseModel], key: str) -> dict:
    """The leaf's uncertainty keys (range, sigma, follows, reason), checked."""
    given = [k for k in SPREAD_KEYS if k in sub]
    if not given:
        if "reason" in sub:
            raise _error(f"{path}: reason without range, sigma or follows")
        return {}
    if len(given) > 1:
        raise _error(f"{path}: give one of range, sigma or follows, not {' and '.join(given)}")
    if not isinstance(sub.get("reason"), str) or not sub["reason"].strip():
        raise _error(f'{path}: {given[0]} needs its reason (reason: "...")')
    value, kind, spec = sub["value"], given[0], sub[given[0]]
    if kind == "range":
        if isinstance(value, list):
            raise _error(
                f"{path}: range is for a scalar number; give sigma per element for a vector"
            )
        if not is_number(value):  # a word, true/false, NaN: was reported as a vector's range
            raise _error(f"{path}: value {value!r} is not a finite number")
        if not (
            isinstance(spec, list)
            and len(spec) == 2
            and all(is_number(v) for v in spec)
            and spec[0] < spec[1]
        ):
            raise _error(
                f"{path}: range must be [lo, hi] with finite numbers lo < hi, got {spec!r}"
            )
        if not spec[0] <= value <= spec[1]:
            raise _error(f"{path}: value {value!r} lies outside its range {spec}")
        lo, hi, unit = field_range(model, [key])
        if (lo != "-inf" and spec[0] < lo) or (hi != "inf" and spec[1] > hi):
            raise _error(f"{path}: range {spec} leaves the allowed [{lo}, {hi}] {unit}".rstrip())
    elif kind == "sigma":
        sigmas = spec if isinstance(spec, list) else [spec]
        if isinstance(value, list) != isinstance(spec, list) or (
            isinstance(value, list) and len(spec) != len(value)
        ):
            raise _error(
                f"{path}: sigma must be a number for a scalar, one per element for a vector"
            )
        if not all(is_number(v) and v >= 0 for v in sigmas):
            raise _error(f"{path}: sigma must be finite and >= 0, got {spec!r}")
    elif not (isinstance(spec, str) and spec.count(".") == 1 and is_number(value)):
        raise _error(
            f"{path}: follows must name another scalar parameter (section.key), got {spec!r}"
        )
    return {kind: spec, "reason": sub["reason"].strip()}


def field_range(model: type[BaseModel], loc: list[str]) -> tuple[Any, Any, str]:
    """(low, high, unit) declared in the schema for the field at ``loc``."""
    field = None
    for key in loc:
        field = model.model_fields.get(key) if model is not None else None
        if field is None:
            return "-inf", "inf", ""
        ann = field.annotation
        model = ann if isinstance(ann, type) and issubclass(ann, BaseModel) else None
    lo, hi = "-inf", "inf"
    for m in field.metadata:
        lo = (
            getattr(m, "ge", None)
            if getattr(m, "ge", None) is not None
            else (getattr(m, "gt", None) if getattr(m, "gt", None) is not None else lo)
        )
        hi = (
            getattr(m, "le", None)
            if getattr(m, "le", None) is not None
            else (getattr(m, "lt", None) if getattr(m, "lt", None) is not None else hi)
        )
    extra = field.json_schema_extra if isinstance(field.json_schema_extra, dict) else {}
    return lo, hi, extra.get("unit", "")


def check_follows(meta: dict, plain: dict) -> None:
    """Each ``follows`` names another non-zero scalar parameter that follows none itself."""
    for key, m in meta.items():
        target = m.get("follows")
        if target is None:
            continue
        if target not in meta or target == key or "follows" in meta[target]:
            raise _error(
                f"{key}: follows {target!r}, which must be another parameter that does not "
                "follow one itself"
            )
        value = value_at(plain, target)
        if not is_number(value) or value == 0:
            raise _error(f"{key}: follows {target!r}, which must be a non-zero scalar number")


def value_at(tree: dict, dotted: str) -> Any:
    """The entry at a dotted key of a nested dict."""
    node: Any = tree
    for k in dotted.split("."):
        node = node[k]
    return node
