"""A parameter file's tree of ``{value, unit, source}`` leaves: stripped to plain values with each
leaf's unit checked against the schema's and its metadata kept (:func:`strip_leaves`), walked leaf
by leaf (:func:`flatten_leaves`), copied (:func:`copy_tree`) and checked for NaN
(:func:`reject_nan`)."""

from __future__ import annotations

import math
from typing import Any, Iterator

from pydantic import BaseModel

from amr_twin.model.config_leaves import LEAF_KEYS, ConfigError, leaf_spread


def _schema_unit(model: type[BaseModel], key: str) -> str | None:
    field = model.model_fields.get(key)
    extra = field.json_schema_extra if field is not None else None
    return extra.get("unit") if isinstance(extra, dict) else None


def is_leaf(node: Any) -> bool:
    """Whether ``node`` is a ``{value, ...}`` leaf."""
    return isinstance(node, dict) and "value" in node


def strip_leaves(node: dict, model: type[BaseModel], prefix: str, meta: dict) -> dict:
    """Turn a tree of {value, unit, source} leaves into plain values; check units."""
    out: dict[str, Any] = {}
    for key, sub in node.items():
        path = f"{prefix}{key}"
        field = model.model_fields.get(key)
        if field is None:
            allowed = ", ".join(model.model_fields)
            raise ConfigError(f"{path}: unknown key (allowed: {allowed})")
        if is_leaf(sub):
            extra = set(sub) - set(LEAF_KEYS)
            if extra:
                raise ConfigError(
                    f"{path}: unknown leaf key(s) {sorted(extra)} (allowed: {', '.join(LEAF_KEYS)})"
                )
            unit = _schema_unit(model, key)
            if "unit" not in sub or "source" not in sub:
                raise ConfigError(f"{path}: a parameter needs value, unit and source")
            if unit is not None and sub["unit"] != unit:
                raise ConfigError(f"{path}: unit '{sub['unit']}' but the schema's is '{unit}'")
            meta[path] = {
                "unit": sub["unit"],
                "source": sub["source"],
                **leaf_spread(sub, path, model, key),
            }
            out[key] = sub["value"]
        elif isinstance(sub, dict):
            sub_model = field.annotation
            if not (isinstance(sub_model, type) and issubclass(sub_model, BaseModel)):
                raise ConfigError(f"{path}: expected a {{value, unit, source}} leaf")
            out[key] = strip_leaves(sub, sub_model, path + ".", meta)
        else:
            raise ConfigError(f"{path}: expected a {{value, unit, source}} leaf, got {sub!r}")
    return out


def copy_tree(tree: dict) -> dict:
    """A copy of ``tree``'s dicts (the values shared)."""
    return {k: copy_tree(v) if isinstance(v, dict) else v for k, v in tree.items()}


def flatten_leaves(tree: dict, prefix: str = "") -> Iterator[tuple[str, Any]]:
    """``(dotted key, value)`` of every leaf (a leaf's ``value``) or plain value of ``tree``."""
    for key, sub in tree.items():
        if is_leaf(sub):
            yield prefix + key, sub["value"]
        elif isinstance(sub, dict):
            yield from flatten_leaves(sub, prefix + key + ".")
        else:
            yield prefix + key, sub


def reject_nan(tree: dict, prefix: str = "") -> None:
    """Refuse a value of ``tree`` that is NaN or infinite (ConfigError naming it)."""
    for key, value in tree.items():
        values = value if isinstance(value, (list, tuple)) else [value]
        if isinstance(value, dict):
            reject_nan(value, f"{prefix}{key}.")
            continue
        for v in values:
            if isinstance(v, float) and not math.isfinite(v):
                raise ConfigError(f"{prefix}{key}: {v!r} must be a finite number")
