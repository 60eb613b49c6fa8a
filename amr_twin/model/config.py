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

from pathlib import Path
from typing import Any

from pydantic import ValidationError, model_validator

from amr_twin.model.config_errors import validation_message
from amr_twin.model.config_estimation import EkfCfg, LidarOdometryCfg, MappingCfg
from amr_twin.model.config_tree import (
    copy_tree,
    flatten_leaves,
    is_leaf,
    reject_nan,
    strip_leaves,
)
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
        plain = strip_leaves(tree, TwinConfig, "", meta)
    except ConfigError as exc:
        raise ConfigError(f"{path}: {exc}" if path is not None else str(exc)) from None
    blame = Blame()
    tree_values = copy_tree(plain)  # the file's values: the kind each parameter takes
    if override_file is not None:
        extra = _read_yaml(Path(override_file))
        try:
            for key, value in flatten_leaves(extra):
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
        reject_nan(plain)
        cfg = TwinConfig.model_validate(plain)
    except ConfigError as exc:
        raise ConfigError(blame.message(str(exc), path)) from None
    except ValidationError as exc:  # a value nobody overrode is the parameter file's: it is named
        raise ConfigError(blame.message(validation_message(exc, TwinConfig), path)) from None
    check_follows(meta, plain)
    return cfg, meta


def with_values(cfg: TwinConfig, overrides: dict[str, Any]) -> TwinConfig:
    """``cfg`` with the values of ``overrides`` (``{"dotted.key": value}``) replaced, validated
    again like a loaded file (raises :class:`ConfigError`); the parameter file is not read again."""
    plain = cfg.model_dump()
    for key, value in overrides.items():
        _set_path(plain, key, value)
    reject_nan(plain)
    try:
        return TwinConfig.model_validate(plain)
    except ValidationError as exc:
        raise ConfigError(validation_message(exc, TwinConfig)) from None


def _override_meta(meta: dict, key: str, leaf: Any, by: str) -> None:
    """Record who replaced ``key``'s value. An override leaf with a source or a spread of its
    own (range, sigma, follows) brings its own description; the file's spread does not
    describe a value someone else chose."""
    if key not in meta:  # a section, not a leaf: _set_path accepted it, validation judges it
        return
    base = meta[key]
    if is_leaf(leaf) and any(k in leaf for k in ("source", "reason") + SPREAD_KEYS):
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


def parameter_table(path: str | Path | None = None) -> list[tuple[str, Any, str, str]]:
    """Rows ``(dotted key, value, unit, source)`` of a parameter file, in file order."""
    rows = []
    meta: dict[str, dict] = {}
    tree = read_tree(path)
    strip_leaves(tree, TwinConfig, "", meta)
    for key, value in flatten_leaves(tree):
        rows.append((key, value, meta[key]["unit"], meta[key]["source"]))
    return rows
