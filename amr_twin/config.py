"""The one validated parameter file of the twin, loaded into typed, frozen objects.

The file (``models/amr/amr.yaml``) holds every physical parameter as a leaf of the
form ``{value: ..., unit: "...", source: "..."}``. :func:`load_config` checks the
shape (no unknown key, every unit equal to the schema's), applies overrides (a
second YAML of plain values or of leaves, and ``key=value`` strings), validates
ranges with pydantic and returns a frozen :class:`TwinConfig`. Errors are raised
as :class:`ConfigError` with a one-line message naming the field and its range.

The section classes (``SimCfg`` ... ``MappingCfg``) are declared in
:mod:`amr_twin.config_sections`; this module assembles them into :class:`TwinConfig`
and holds the loading (YAML leaves to plain values, overrides, error messages).
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any, Iterator

import yaml
from pydantic import BaseModel, ValidationError, model_validator

from .config_sections import (BatteryCfg, CasterCfg, ChassisCfg, ComponentsCfg, DeckCfg, DriverCfg,
                              EkfCfg, ImuCfg, LidarCfg, LidarOdometryCfg, MappingCfg, MotorCfg,
                              PayloadCfg, Section, SimCfg, UwbCfg, WheelCfg)
from .paths import MODEL_DIR

DEFAULT_CONFIG = MODEL_DIR / "amr.yaml"


class ConfigError(ValueError):
    """A parameter file or override is invalid; the message is one line."""


class TwinConfig(Section):
    """Every physical parameter of the twin, validated and frozen."""

    sim: SimCfg
    chassis: ChassisCfg
    deck: DeckCfg
    components: ComponentsCfg
    wheel: WheelCfg
    caster: CasterCfg
    payload: PayloadCfg
    motor_left: MotorCfg
    motor_right: MotorCfg
    driver: DriverCfg
    battery: BatteryCfg
    imu: ImuCfg
    lidar: LidarCfg
    uwb: UwbCfg
    ekf: EkfCfg
    lidar_odometry: LidarOdometryCfg
    mapping: MappingCfg

    @model_validator(mode="after")
    def _geometry_consistent(self) -> "TwinConfig":
        c, w, k, p = self.chassis, self.wheel, self.caster, self.payload
        inner_y = w.separation_m / 2 - w.width_m / 2
        if c.width_m / 2 > inner_y - 0.002:
            raise ValueError(f"chassis.width_m: must be < {2 * (inner_y - 0.002):.3f} m "
                             "(the frame must clear the wheels)")
        if k.x_m > c.length_m / 2 or k.y_m > c.width_m / 2:
            raise ValueError(f"caster.x_m, caster.y_m: must be within [0, {c.length_m / 2}] x [0, {c.width_m / 2}] m "
                             "(the chassis footprint)")
        if p.mass_kg > 0:
            hx, hy = c.length_m / 2, c.width_m / 2
            x, y = p.xy_m
            sx, sy = p.size_m[0] / 2, p.size_m[1] / 2
            if abs(x) + sx > hx + 1e-9 or abs(y) + sy > hy + 1e-9:
                raise ValueError(
                    f"payload.xy_m: ({x}, {y}) with size {p.size_m[:2]} is outside the deck: "
                    f"|x| must be <= {hx - sx:.3f} m and |y| <= {hy - sy:.3f} m")
        return self


# --------------------------------------------------------------------------- loading
def _schema_unit(model: type[BaseModel], key: str) -> str | None:
    field = model.model_fields.get(key)
    extra = field.json_schema_extra if field is not None else None
    return extra.get("unit") if isinstance(extra, dict) else None


def _is_leaf(node: Any) -> bool:
    return isinstance(node, dict) and "value" in node


def _strip(node: dict, model: type[BaseModel], prefix: str, meta: dict) -> dict:
    """Turn a tree of {value, unit, source} leaves into plain values; check units."""
    out: dict[str, Any] = {}
    for key, sub in node.items():
        path = f"{prefix}{key}"
        field = model.model_fields.get(key)
        if field is None:
            allowed = ", ".join(model.model_fields)
            raise ConfigError(f"{path}: unknown key (allowed: {allowed})")
        if _is_leaf(sub):
            extra = set(sub) - {"value", "unit", "source"}
            if extra:
                raise ConfigError(f"{path}: unknown leaf key(s) {sorted(extra)} (allowed: value, unit, source)")
            unit = _schema_unit(model, key)
            if "unit" not in sub or "source" not in sub:
                raise ConfigError(f"{path}: a parameter needs value, unit and source")
            if unit is not None and sub["unit"] != unit:
                raise ConfigError(f"{path}: unit '{sub['unit']}' but the schema's is '{unit}'")
            meta[path] = {"unit": sub["unit"], "source": sub["source"]}
            out[key] = sub["value"]
        elif isinstance(sub, dict):
            sub_model = field.annotation
            if not (isinstance(sub_model, type) and issubclass(sub_model, BaseModel)):
                raise ConfigError(f"{path}: expected a {{value, unit, source}} leaf")
            out[key] = _strip(sub, sub_model, path + ".", meta)
        else:
            raise ConfigError(f"{path}: expected a {{value, unit, source}} leaf, got {sub!r}")
    return out


def _set_path(tree: dict, dotted: str, value: Any) -> None:
    keys = dotted.split(".")
    node = tree
    for k in keys[:-1]:
        if not isinstance(node.get(k), dict):
            raise ConfigError(f"{dotted}: unknown key")
        node = node[k]
    if keys[-1] not in node:
        raise ConfigError(f"{dotted}: unknown key")
    node[keys[-1]] = value


def _flatten(tree: dict, prefix: str = "") -> Iterator[tuple[str, Any]]:
    for key, sub in tree.items():
        if _is_leaf(sub):
            yield prefix + key, sub["value"]
        elif isinstance(sub, dict):
            yield from _flatten(sub, prefix + key + ".")
        else:
            yield prefix + key, sub


def parse_assignment(text: str) -> tuple[str, Any]:
    """Parse ``key=value`` (value in YAML syntax, e.g. ``payload.xy_m=[0.1,0]``)."""
    if "=" not in text:
        raise ConfigError(f"--set {text!r}: expected key=value")
    key, raw = text.split("=", 1)
    try:
        value = yaml.safe_load(raw)
    except yaml.YAMLError as exc:
        raise ConfigError(f"--set {key}: cannot parse value {raw!r}") from exc
    return key.strip(), value


def _field_range(model: type[BaseModel], loc: list[str]) -> tuple[Any, Any, str]:
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
        lo = getattr(m, "ge", None) if getattr(m, "ge", None) is not None else (
            getattr(m, "gt", None) if getattr(m, "gt", None) is not None else lo)
        hi = getattr(m, "le", None) if getattr(m, "le", None) is not None else (
            getattr(m, "lt", None) if getattr(m, "lt", None) is not None else hi)
    extra = field.json_schema_extra if isinstance(field.json_schema_extra, dict) else {}
    return lo, hi, extra.get("unit", "")


def _format_error(exc: ValidationError, model: type[BaseModel]) -> str:
    err = exc.errors()[0]
    loc = [str(p) for p in err["loc"] if not isinstance(p, int)]
    msg = err["msg"].replace("Value error, ", "")
    value = err.get("input")
    if any(k in (err.get("ctx") or {}) for k in ("ge", "gt", "le", "lt")):
        lo, hi, unit = _field_range(model, loc)
        if (lo, hi) == ("-inf", "inf"):  # element constraint of a vector
            ctx = err["ctx"]
            lo = ctx.get("ge", ctx.get("gt", lo))
            hi = ctx.get("le", ctx.get("lt", hi))
        msg = f"{value!r} is out of range: allowed [{lo}, {hi}] {unit}".rstrip()
    elif err["type"] == "finite_number":
        msg = f"{value!r}: must be a finite number"
    return f"{'.'.join(loc)}: {msg}" if loc else msg


def load_config(path: str | Path | None = None, *, override_file: str | Path | None = None,
                sets: list[str] | tuple[str, ...] = (), overrides: dict[str, Any] | None = None,
                ) -> TwinConfig:
    """Load, override and validate the parameter file.

    Parameters
    ----------
    path : path of the parameter file (default ``models/amr/amr.yaml``).
    override_file : a second YAML, same tree, whose leaves are plain values or
        ``{value, ...}`` leaves; it replaces the matching values.
    sets : ``"dotted.key=value"`` strings, applied last.
    overrides : ``{"dotted.key": value}``, applied after ``sets`` (API use).
    """
    tree = read_tree(path)
    meta: dict[str, dict] = {}
    try:
        plain = _strip(tree, TwinConfig, "", meta)
    except ConfigError as exc:
        raise ConfigError(f"{path}: {exc}" if path is not None else str(exc)) from None
    if override_file is not None:
        extra = _read_yaml(Path(override_file))
        try:
            for key, value in _flatten(extra):
                _set_path(plain, key, value)
        except ConfigError as exc:
            raise ConfigError(f"{override_file}: {exc}") from None
    for text in sets:
        _set_path(plain, *parse_assignment(text))
    for key, value in (overrides or {}).items():
        _set_path(plain, key, value)
    _reject_nan(plain)
    try:
        return TwinConfig.model_validate(plain)
    except ValidationError as exc:
        raise ConfigError(_format_error(exc, TwinConfig)) from None


def _reject_nan(tree: dict, prefix: str = "") -> None:
    for key, value in tree.items():
        values = value if isinstance(value, (list, tuple)) else [value]
        if isinstance(value, dict):
            _reject_nan(value, f"{prefix}{key}.")
            continue
        for v in values:
            if isinstance(v, float) and not math.isfinite(v):
                raise ConfigError(f"{prefix}{key}: {v!r} must be a finite number")


def _read_yaml(path: Path) -> dict:
    try:
        data = yaml.safe_load(path.read_text())
    except FileNotFoundError:
        raise ConfigError(f"{path}: no such parameter file") from None
    except IsADirectoryError:
        raise ConfigError(f"{path}: is a folder, not a parameter file (YAML)") from None
    except UnicodeDecodeError:
        raise ConfigError(f"{path}: not a text file (a YAML parameter file is expected)") from None
    except OSError as exc:
        raise ConfigError(f"{path}: cannot be read ({exc.strerror or exc})") from None
    except yaml.YAMLError as exc:
        raise ConfigError(f"{path}: not valid YAML ({str(exc).splitlines()[0]})") from None
    if not isinstance(data, dict):
        raise ConfigError(f"{path}: expected a mapping at the top level")
    return data


def read_tree(path: str | Path | None = None) -> dict:
    """The raw YAML tree of a parameter file (with units and sources)."""
    return _read_yaml(Path(path) if path is not None else DEFAULT_CONFIG)


def parameter_table(path: str | Path | None = None) -> list[tuple[str, Any, str, str]]:
    """Rows ``(dotted key, value, unit, source)`` of a parameter file, in file order."""
    rows = []
    meta: dict[str, dict] = {}
    tree = read_tree(path)
    _strip(tree, TwinConfig, "", meta)
    for key, value in _flatten(tree):
        rows.append((key, value, meta[key]["unit"], meta[key]["source"]))
    return rows
