"""The one validated parameter file of the twin, loaded into typed, frozen objects.

The file (``models/amr/amr.yaml``) holds every physical parameter as a leaf of the
form ``{value: ..., unit: "...", source: "..."}``. :func:`load_config` checks the
shape (no unknown key, every unit equal to the schema's), applies overrides (a
second YAML of plain values or of leaves, and ``key=value`` strings), validates
ranges with pydantic and returns a frozen :class:`TwinConfig`. Errors are raised
as :class:`ConfigError` with a one-line message naming the field and its range.

A leaf may also say how uncertain its value is, with the reason (``reason:``), by
one of: ``range: [lo, hi]`` (drawn uniformly; the value inside, the bounds inside the
schema's), ``sigma: s`` (normal, same unit; a list of one sigma per element for a
vector; ``sigma: 0`` holds the value exact) or ``follows: other.key`` (drawn with the
same relative deviation as that parameter). Without any, the spread defaults from the
source's kind (:mod:`amr_twin.calibration.uncertainty`). :func:`load_parameters` returns these
leaf descriptions next to the configuration.

The section classes (``SimCfg`` ... ``MappingCfg``) are declared in
:mod:`amr_twin.model.config_sections`; this module assembles them into :class:`TwinConfig`
and holds the loading (YAML leaves to plain values, overrides, error messages).
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any, Iterator

from pydantic import BaseModel, ValidationError, model_validator

from amr_twin.model.config_estimation import EkfCfg, LidarOdometryCfg, MappingCfg
from amr_twin.model.config_sections import (
    BatteryCfg,
    CasterCfg,
    ChassisCfg,
    ComponentsCfg,
    DeckCfg,
    DriverBoardCfg,
    DriverCfg,
    MotorCfg,
    PayloadCfg,
    Section,
    SimCfg,
    WheelCfg,
)
from amr_twin.model.config_sensors import ImuCfg, LidarCfg, UwbCfg
from amr_twin.model.config_actors import ActorsCfg
from amr_twin.model.config_navigation import NavigationCfg
from amr_twin.model.config_leaves import ConfigError  # noqa: F401 - the parameter files' error, raised here too
from amr_twin.model.config_leaves import (
    LEAF_KEYS,
    SPREAD_KEYS,
    check_follows,
    leaf_spread,
    value_at,
)
from amr_twin.model.config_leaves import field_range as _field_range
from amr_twin.model.config_overrides import Blame, check_assignment, check_kind, parse_assignment
from amr_twin.model.config_overrides import set_path as _set_path
from amr_twin.model.parameter_tree import read_tree
from amr_twin.model.parameter_tree import read_yaml as _read_yaml

"""libyaml's safe loader when PyYAML has it (amr.yaml in ~3 ms instead of ~30 ms), else the Python
one."""


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
    driver_left: DriverBoardCfg
    driver_right: DriverBoardCfg
    battery: BatteryCfg
    imu: ImuCfg
    lidar: LidarCfg
    uwb: UwbCfg
    ekf: EkfCfg
    lidar_odometry: LidarOdometryCfg
    mapping: MappingCfg
    actors: ActorsCfg
    navigation: NavigationCfg

    @property
    def half_width_m(self) -> float:
        """Half the robot's width across its drive wheels' outer faces (the chassis' if wider), m:
        the footprint navigation, the people giving way and the route checks take for the robot
        (0.265)."""
        return max(self.chassis.width_m / 2, self.wheel.separation_m / 2 + self.wheel.width_m / 2)

    @model_validator(mode="after")
    def _geometry_consistent(self) -> "TwinConfig":
        c, w, k, p = self.chassis, self.wheel, self.caster, self.payload
        inner_y = w.separation_m / 2 - w.width_m / 2
        if c.width_m / 2 > inner_y - 0.002:
            raise ValueError(
                f"chassis.width_m: must be < {2 * (inner_y - 0.002):.3f} m "
                "(the frame must clear the wheels)"
            )
        if k.x_m > c.length_m / 2 or k.y_m > c.width_m / 2:
            raise ValueError(
                f"caster.x_m, caster.y_m: must be within [0, {c.length_m / 2}] x [0, "
                f"{c.width_m / 2}] m "
                "(the chassis footprint)"
            )
        if p.mass_kg > 0:
            hx, hy = c.length_m / 2, c.width_m / 2
            x, y = p.xy_m
            sx, sy = p.size_m[0] / 2, p.size_m[1] / 2
            if abs(x) + sx > hx + 1e-9 or abs(y) + sy > hy + 1e-9:
                raise ValueError(
                    f"payload.xy_m: ({x}, {y}) with size {p.size_m[:2]} is outside the deck: "
                    f"|x| must be <= {hx - sx:.3f} m and |y| <= {hy - sy:.3f} m"
                )
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
            out[key] = _strip(sub, sub_model, path + ".", meta)
        else:
            raise ConfigError(f"{path}: expected a {{value, unit, source}} leaf, got {sub!r}")
    return out


def _copy(tree: dict) -> dict:
    return {k: _copy(v) if isinstance(v, dict) else v for k, v in tree.items()}


def _flatten(tree: dict, prefix: str = "") -> Iterator[tuple[str, Any]]:
    for key, sub in tree.items():
        if _is_leaf(sub):
            yield prefix + key, sub["value"]
        elif isinstance(sub, dict):
            yield from _flatten(sub, prefix + key + ".")
        else:
            yield prefix + key, sub


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
        left, right = _open_ends(model, loc, err["ctx"])
        msg = (
            f"{value!r} is out of range: allowed {'(' if left else '['}{lo}, "
            f"{hi}{')' if right else ']'} {unit}"
        ).rstrip()
    elif err["type"] == "finite_number":
        msg = f"{value!r}: must be a finite number"
    elif err["type"] in ("missing", "too_short", "too_long") and isinstance(value, (list, tuple)):
        size = _tuple_size(model, loc)  # a fixed-size vector given another number of values
        msg = f"{list(value)!r} has {len(value)} value(s); it takes {size}" if size else msg
    elif err["type"] == "missing":  # pydantic's "Field required"
        msg = "missing: give its {value, unit, source} leaf"
    elif err["type"] in (
        "dict_type",
        "model_type",
        "model_attributes_type",
    ):  # "a valid dictionary or instance of"
        msg = f"{value!r} is not a section: give its parameters as keys"
    elif err["type"] in _KINDS:  # "Input should be a valid number, unable to parse ..."
        msg = f"{value!r} is not {_KINDS[err['type']]}"
    return f"{'.'.join(loc)}: {msg}" if loc else msg


_KINDS = {
    "float_parsing": "a number",
    "float_type": "a number",
    "int_parsing": "a whole number",
    "int_type": "a whole number",
    "int_from_float": "a whole number",
    "bool_parsing": "true or false",
    "bool_type": "true or false",
    "string_type": "a word",
    "tuple_type": "a list",
    "list_type": "a list",
}
"""pydantic's error types of a value of the wrong kind, and the kind in the project's words."""


def _open_ends(model: type[BaseModel], loc: list[str], ctx: dict) -> tuple[bool, bool]:
    """Whether the range of the field at ``loc`` excludes its low and its high end (``gt``, ``lt``):
    an exclusive bound was printed as ``[0.0, 3.0]`` for a refused 0."""
    field: Any = None
    for key in loc:
        fields = getattr(model, "model_fields", None) or {}
        field = fields.get(key)
        if field is None:
            return "gt" in ctx, "lt" in ctx
        model = field.annotation
    metadata = getattr(field, "metadata", ())
    return (
        any(getattr(m, "gt", None) is not None for m in metadata) or "gt" in ctx,
        any(getattr(m, "lt", None) is not None for m in metadata) or "lt" in ctx,
    )


def _tuple_size(model: type[BaseModel], loc: list[str]) -> int | None:
    """The number of values of the fixed-size tuple field at ``loc`` (None: not one)."""
    import typing

    annotation: Any = model
    for key in loc:
        fields = getattr(annotation, "model_fields", None)
        if not fields or key not in fields:
            return None
        annotation = fields[key].annotation
    args = typing.get_args(annotation)
    return (
        len(args)
        if typing.get_origin(annotation) is tuple and args and Ellipsis not in args
        else None
    )


def load_config(
    path: str | Path | None = None,
    *,
    override_file: str | Path | None = None,
    sets: list[str] | tuple[str, ...] = (),
    overrides: dict[str, Any] | None = None,
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
    return load_parameters(path, override_file=override_file, sets=sets, overrides=overrides)[0]


def load_parameters(
    path: str | Path | None = None,
    *,
    override_file: str | Path | None = None,
    sets: list[str] | tuple[str, ...] = (),
    overrides: dict[str, Any] | None = None,
) -> tuple[TwinConfig, dict[str, dict]]:
    """:func:`load_config`, and what the files say of each leaf.

    Returns
    -------
    (TwinConfig, dict) : the configuration, and per dotted key ``{"unit", "source"}`` with
    the leaf's ``range`` / ``sigma`` / ``follows`` and ``reason`` when given. A value
    replaced by an override carries ``set_by`` (``--params FILE``, ``--set``,
    ``override``); an override leaf with a source of its own replaces the file's
    description (source and spread) instead.
    """
    tree = read_tree(path)
    meta: dict[str, dict] = {}
    try:
        plain = _strip(tree, TwinConfig, "", meta)
    except ConfigError as exc:
        raise ConfigError(f"{path}: {exc}" if path is not None else str(exc)) from None
    blame = Blame()
    tree_values = _copy(plain)  # the file's values: the kind each parameter takes
    if override_file is not None:
        extra = _read_yaml(Path(override_file))
        try:
            for key, value in _flatten(extra):
                _set_path(plain, key, value)
                if key in meta:
                    check_kind(key, value, meta, value_at(tree_values, key))
                _override_meta(meta, key, value_at(extra, key), f"--params {override_file}")
                blame.set(key, str(override_file))
        except ConfigError as exc:
            raise ConfigError(f"{override_file}: {exc}") from None
    given: dict[str, tuple[str, Any]] = {}
    for text in sets:
        key, value = parse_assignment(text)
        if key in given and given[key][1] != value:  # the last one won, the first was ignored
            raise ConfigError(
                f"--set {key}: given twice with different values ({given[key][0]!r} and {text!r}); "
                "give it once"
            )
        given[key] = (text, value)
        check_assignment(text, key, value, meta, tree_values)
        _set_path(plain, key, value)
        _override_meta(meta, key, None, "--set")
        blame.set(key, f"--set {text!r}")
    for key, value in (overrides or {}).items():
        _set_path(plain, key, value)
        _override_meta(meta, key, None, "override")
    try:
        _reject_nan(plain)
        cfg = TwinConfig.model_validate(plain)
    except ConfigError as exc:
        raise ConfigError(blame.message(str(exc), path)) from None
    except ValidationError as exc:  # a value nobody overrode is the parameter file's: it is named
        raise ConfigError(blame.message(_format_error(exc, TwinConfig), path)) from None
    check_follows(meta, plain)
    return cfg, meta


def with_values(cfg: TwinConfig, overrides: dict[str, Any]) -> TwinConfig:
    """``cfg`` with the values of ``overrides`` (``{"dotted.key": value}``) replaced, validated
    again like a loaded file (raises :class:`ConfigError`); the parameter file is not read again."""
    plain = cfg.model_dump()
    for key, value in overrides.items():
        _set_path(plain, key, value)
    _reject_nan(plain)
    try:
        return TwinConfig.model_validate(plain)
    except ValidationError as exc:
        raise ConfigError(_format_error(exc, TwinConfig)) from None


def _override_meta(meta: dict, key: str, leaf: Any, by: str) -> None:
    """Record who replaced ``key``'s value. An override leaf with a source or a spread of its
    own (range, sigma, follows) brings its own description; the file's spread does not
    describe a value someone else chose."""
    if key not in meta:  # a section, not a leaf: _set_path accepted it, validation judges it
        return
    base = meta[key]
    if _is_leaf(leaf) and any(k in leaf for k in ("source", "reason") + SPREAD_KEYS):
        section, name = key.rsplit(".", 1)
        model: Any = TwinConfig
        for part in section.split("."):
            model = model.model_fields[part].annotation
        extra = set(leaf) - set(LEAF_KEYS)
        if extra:
            raise ConfigError(
                f"{key}: unknown leaf key(s) {sorted(extra)} (allowed: {', '.join(LEAF_KEYS)})"
            )
        meta[key] = {
            "unit": base["unit"],
            "source": leaf.get("source", base["source"]),
            **leaf_spread(leaf, key, model, name),
        }
    else:
        meta[key] = {"unit": base["unit"], "source": base["source"], "set_by": by}


def _reject_nan(tree: dict, prefix: str = "") -> None:
    for key, value in tree.items():
        values = value if isinstance(value, (list, tuple)) else [value]
        if isinstance(value, dict):
            _reject_nan(value, f"{prefix}{key}.")
            continue
        for v in values:
            if isinstance(v, float) and not math.isfinite(v):
                raise ConfigError(f"{prefix}{key}: {v!r} must be a finite number")


def parameter_table(path: str | Path | None = None) -> list[tuple[str, Any, str, str]]:
    """Rows ``(dotted key, value, unit, source)`` of a parameter file, in file order."""
    rows = []
    meta: dict[str, dict] = {}
    tree = read_tree(path)
    _strip(tree, TwinConfig, "", meta)
    for key, value in _flatten(tree):
        rows.append((key, value, meta[key]["unit"], meta[key]["source"]))
    return rows
