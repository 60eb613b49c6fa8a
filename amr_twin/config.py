"""The one validated parameter file of the twin, loaded into typed, frozen objects.

The file (``models/amr/amr.yaml``) holds every physical parameter as a leaf of the
form ``{value: ..., unit: "...", source: "..."}``. :func:`load_config` checks the
shape (no unknown key, every unit equal to the schema's), applies overrides (a
second YAML of plain values or of leaves, and ``key=value`` strings), validates
ranges with pydantic and returns a frozen :class:`TwinConfig`. Errors are raised
as :class:`ConfigError` with a one-line message naming the field and its range.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Annotated, Any, Iterator

import numpy as np
import yaml
from pydantic import BaseModel, ConfigDict, Field, ValidationError, model_validator

from .paths import MODEL_DIR

DEFAULT_CONFIG = MODEL_DIR / "amr.yaml"


class ConfigError(ValueError):
    """A parameter file or override is invalid; the message is one line."""


def P(default: Any = ..., *, unit: str, ge: float | None = None, le: float | None = None,
      gt: float | None = None, lt: float | None = None) -> Any:
    """A physical parameter field: its unit and range travel with the schema."""
    return Field(default, ge=ge, le=le, gt=gt, lt=lt, json_schema_extra={"unit": unit})


class _Section(BaseModel):
    model_config = ConfigDict(frozen=True, extra="forbid", allow_inf_nan=False)


Vec3 = tuple[float, float, float]
_NonNeg = Annotated[float, Field(ge=0.0)]
_Pos = Annotated[float, Field(gt=0.0)]
NonNegVec3 = tuple[_NonNeg, _NonNeg, _NonNeg]
PosVec3 = tuple[_Pos, _Pos, _Pos]


class SimCfg(_Section):
    timestep_s: float = P(unit="s", ge=2e-4, le=0.002)
    floor_friction: float = P(unit="1", ge=0.05, le=2.0)
    gravity_m_s2: float = P(unit="m/s^2", ge=0.0, le=20.0)


class ChassisCfg(_Section):
    length_m: float = P(unit="m", ge=0.3, le=1.5)
    width_m: float = P(unit="m", ge=0.25, le=0.46)
    floor_a_z_m: float = P(unit="m", ge=0.04, le=0.2)
    floor_b_z_m: float = P(unit="m", ge=0.1, le=0.6)
    floor_c_z_m: float = P(unit="m", ge=0.2, le=1.0)
    tube_outer_m: float = P(unit="m", ge=0.01, le=0.06)
    tube_wall_m: float = P(unit="m", ge=0.0005, le=0.005)
    sheet_thickness_m: float = P(unit="m", ge=0.0005, le=0.005)
    steel_density_kg_m3: float = P(unit="kg/m^3", ge=7000, le=8500)

    @model_validator(mode="after")
    def _floors_ordered(self) -> "ChassisCfg":
        if not self.floor_a_z_m < self.floor_b_z_m < self.floor_c_z_m:
            raise ValueError("chassis.floor_*_z_m: floor_a_z_m < floor_b_z_m < floor_c_z_m must hold")
        if self.tube_wall_m * 2 >= self.tube_outer_m:
            raise ValueError("chassis.tube_wall_m: must be less than half of tube_outer_m")
        return self


class DeckCfg(_Section):
    thickness_m: float = P(unit="m", ge=0.001, le=0.02)
    density_kg_m3: float = P(unit="kg/m^3", ge=2000, le=3000)


class ComponentCfg(_Section):
    mass_kg: float = P(unit="kg", ge=0.0, le=50.0)
    size_m: NonNegVec3 = P(unit="m")
    pos_m: Vec3 = P(unit="m")


class ComponentsCfg(_Section):
    battery: ComponentCfg
    charger: ComponentCfg
    mini_pc: ComponentCfg
    electronics: ComponentCfg
    drivers: ComponentCfg
    lidar: ComponentCfg
    imu: ComponentCfg

    def items(self) -> Iterator[tuple[str, ComponentCfg]]:
        for name in type(self).model_fields:
            yield name, getattr(self, name)


class WheelCfg(_Section):
    radius_m: float = P(unit="m", ge=0.05, le=0.3)
    width_m: float = P(unit="m", ge=0.01, le=0.15)
    separation_m: float = P(unit="m", ge=0.2, le=1.0)
    mass_kg: float = P(unit="kg", gt=0.1, le=20.0)
    rotor_fraction: float = P(unit="1", ge=0.1, le=1.0)
    friction: float = P(unit="1", ge=0.1, le=2.0)


class CasterCfg(_Section):
    ball_diameter_m: float = P(unit="m", ge=0.01, le=0.12)
    x_m: float = P(unit="m", ge=0.1, le=0.7)
    y_m: float = P(unit="m", ge=0.05, le=0.3)
    stiffness_n_m: float = P(unit="N/m", ge=100.0, le=1e6)
    damping_n_s_m: float = P(unit="N*s/m", ge=1.0, le=1e5)
    preload_n: float = P(unit="N", ge=0.0, le=500.0)
    travel_m: float = P(unit="m", ge=0.001, le=0.05)
    mass_kg: float = P(unit="kg", gt=0.0, le=2.0)


class PayloadCfg(_Section):
    mass_kg: float = P(unit="kg", ge=0.0, le=200.0)
    size_m: PosVec3 = P(unit="m")
    xy_m: tuple[float, float] = P(unit="m")


class MotorCfg(_Section):
    ke_v_s_rad: float = P(unit="V*s/rad", gt=0.05, le=3.0)
    resistance_ohm: float = P(unit="ohm", gt=0.01, le=10.0)
    current_limit_a: float = P(unit="A", gt=0.5, le=60.0)
    friction_nm: float = P(unit="N*m", ge=0.0, le=5.0)
    damping_nm_s_rad: float = P(unit="N*m*s/rad", ge=0.0, le=5.0)


class DriverCfg(_Section):
    gain: float = P(unit="1", gt=0.1, le=20.0)
    deadband_duty: float = P(unit="1", ge=0.0, le=0.5)
    brake_damping_nm_s_rad: float = P(unit="N*m*s/rad", gt=0.0, le=1e4)


class BatteryCfg(_Section):
    capacity_ah: float = P(unit="A*h", gt=0.1, le=200.0)
    v_full_v: float = P(unit="V", gt=1.0, le=100.0)
    v_nominal_v: float = P(unit="V", gt=1.0, le=100.0)
    v_empty_v: float = P(unit="V", gt=1.0, le=100.0)
    internal_resistance_ohm: float = P(unit="ohm", ge=0.0, le=2.0)
    soc_initial: float = P(unit="1", ge=0.0, le=1.0)

    @model_validator(mode="after")
    def _voltages_ordered(self) -> "BatteryCfg":
        if not self.v_empty_v < self.v_nominal_v < self.v_full_v:
            raise ValueError("battery.v_*_v: v_empty_v < v_nominal_v < v_full_v must hold")
        return self


class ImuCfg(_Section):
    """Adafruit 9-DOF IMU: LSM303DLHC accelerometer/magnetometer + L3GD20 gyroscope (SI units)."""

    rate_hz: float = P(unit="Hz", ge=1.0, le=1000.0)
    accel_range_m_s2: float = P(unit="m/s^2", gt=0.0, le=200.0)
    accel_resolution_m_s2: float = P(unit="m/s^2", ge=0.0, le=1.0)
    accel_noise_density_m_s2_sqrt_hz: float = P(unit="m/s^2/sqrt(Hz)", ge=0.0, le=0.1)
    accel_bias_sigma_m_s2: float = P(unit="m/s^2", ge=0.0, le=5.0)
    accel_bias_walk_m_s2_sqrt_s: float = P(unit="m/s^2/sqrt(s)", ge=0.0, le=0.1)
    accel_scale_sigma: float = P(unit="1", ge=0.0, le=0.1)
    gyro_range_rad_s: float = P(unit="rad/s", gt=0.0, le=100.0)
    gyro_resolution_rad_s: float = P(unit="rad/s", ge=0.0, le=0.1)
    gyro_noise_density_rad_s_sqrt_hz: float = P(unit="rad/s/sqrt(Hz)", ge=0.0, le=0.1)
    gyro_bias_sigma_rad_s: float = P(unit="rad/s", ge=0.0, le=1.0)
    gyro_bias_walk_rad_s_sqrt_s: float = P(unit="rad/s/sqrt(s)", ge=0.0, le=0.01)
    gyro_scale_sigma: float = P(unit="1", ge=0.0, le=0.1)
    mag_range_t: float = P(unit="T", gt=0.0, le=1e-2)
    mag_resolution_xy_t: float = P(unit="T", ge=0.0, le=1e-5)
    mag_resolution_z_t: float = P(unit="T", ge=0.0, le=1e-5)
    mag_noise_t: float = P(unit="T", ge=0.0, le=1e-4)
    mag_bias_sigma_t: float = P(unit="T", ge=0.0, le=1e-3)


class LidarCfg(_Section):
    """Slamtec RPLIDAR A1 (A1M8) 2D scanner."""

    scan_rate_hz: float = P(unit="Hz", ge=1.0, le=10.0)
    sample_rate_hz: int = P(unit="Hz", ge=2000, le=8000)
    range_min_m: float = P(unit="m", gt=0.0, le=1.0)
    range_max_m: float = P(unit="m", gt=1.0, le=40.0)
    range_noise_frac: float = P(unit="1", ge=0.0, le=0.1)
    range_noise_floor_m: float = P(unit="m", ge=0.0, le=0.1)
    range_resolution_m: float = P(unit="m", ge=0.0, le=0.01)

    @model_validator(mode="after")
    def _sample_rate_is_a_mode(self) -> "LidarCfg":
        if self.sample_rate_hz not in (2000, 4000, 8000):
            raise ValueError("lidar.sample_rate_hz: must be 2000, 4000 or 8000 (A1 standard/express/boost)")
        return self


_Coord = Annotated[float, Field(ge=-1000.0, le=1000.0)]


class UwbCfg(_Section):
    """UWB two-way ranging (Decawave DW1000 / DWM1000 tag and anchors), SI units.

    The anchors stand in the world (``map``) frame at ``(anchors_x_m[i], anchors_y_m[i],
    anchor_z_m)``; the tag is at ``tag_pos_m`` in ``base_link``.
    """

    rate_hz: float = P(unit="Hz", ge=0.5, le=100.0)
    range_noise_sigma_m: float = P(unit="m", ge=0.0, le=1.0)
    dropout_prob: float = P(unit="1", ge=0.0, le=0.9)
    nlos_prob: float = P(unit="1", ge=0.0, le=1.0)
    nlos_bias_m: float = P(unit="m", ge=0.0, le=10.0)
    max_range_m: float = P(unit="m", ge=1.0, le=300.0)
    anchors_x_m: tuple[_Coord, ...] = P(unit="m")
    anchors_y_m: tuple[_Coord, ...] = P(unit="m")
    anchor_z_m: float = P(unit="m", ge=0.0, le=30.0)
    tag_pos_m: Vec3 = P(unit="m")

    @model_validator(mode="after")
    def _anchors_paired(self) -> "UwbCfg":
        n = len(self.anchors_x_m)
        if n != len(self.anchors_y_m):
            raise ValueError(f"uwb.anchors_y_m: must have as many values as anchors_x_m ({n})")
        if not 3 <= n <= 16:
            raise ValueError(f"uwb.anchors_x_m: {n} anchors, allowed [3, 16] (2D position needs 3)")
        return self

    @property
    def anchors_xy_m(self):
        """Anchor positions in the world frame, ndarray shape (n_anchors, 2), m."""
        return np.column_stack((self.anchors_x_m, self.anchors_y_m)).astype(np.float64)


class EkfCfg(_Section):
    """EKF of ``controllers/ekf.py`` (robot_localization ``ekf_node`` in two_d_mode), SI units.

    Process noise is white acceleration; measurement sigmas are those the filter
    assumes (not the simulated sensors' own), the Mahalanobis gate is in sigmas.
    """

    accel_sigma_m_s2: float = P(unit="m/s^2", gt=0.0, le=20.0)
    alpha_sigma_rad_s2: float = P(unit="rad/s^2", gt=0.0, le=50.0)
    gyro_bias_walk_rad_s_sqrt_s: float = P(unit="rad/s/sqrt(s)", ge=0.0, le=0.1)
    odom_v_sigma_m_s: float = P(unit="m/s", gt=0.0, le=5.0)
    odom_w_sigma_rad_s: float = P(unit="rad/s", gt=0.0, le=10.0)
    odom_differential: bool = P(unit="bool")
    gyro_w_sigma_rad_s: float = P(unit="rad/s", gt=0.0, le=10.0)
    uwb_range_sigma_m: float = P(unit="m", gt=0.0, le=10.0)
    initial_xy_sigma_m: float = P(unit="m", gt=0.0, le=100.0)
    initial_yaw_sigma_rad: float = P(unit="rad", gt=0.0, le=10.0)
    initial_v_sigma_m_s: float = P(unit="m/s", gt=0.0, le=10.0)
    initial_w_sigma_rad_s: float = P(unit="rad/s", gt=0.0, le=10.0)
    initial_gyro_bias_sigma_rad_s: float = P(unit="rad/s", gt=0.0, le=5.0)
    mahalanobis_gate: float = P(unit="1", gt=0.0, le=1000.0)
    imu_rest_calibration_s: float = P(unit="s", ge=0.0, le=60.0)
    rest_speed_m_s: float = P(unit="m/s", ge=0.0, le=0.5)


class LidarOdometryCfg(_Section):
    """kiss-icp settings of ``controllers/lidar_odometry.py`` (plain keyword arguments)."""

    voxel_size_m: float = P(unit="m", ge=0.02, le=2.0)
    max_range_m: float = P(unit="m", gt=0.5, le=100.0)
    min_range_m: float = P(unit="m", ge=0.0, le=5.0)
    deskew: bool = P(unit="bool")

    @model_validator(mode="after")
    def _ranges_ordered(self) -> "LidarOdometryCfg":
        if self.min_range_m >= self.max_range_m:
            raise ValueError("lidar_odometry.min_range_m: must be less than max_range_m")
        return self


class MappingCfg(_Section):
    """Occupancy grid of ``controllers/occupancy_grid.py``."""

    resolution_m: float = P(unit="m", ge=0.01, le=1.0)
    margin_m: float = P(unit="m", ge=0.0, le=20.0)


class TwinConfig(_Section):
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
    plain = _strip(tree, TwinConfig, "", meta)
    if override_file is not None:
        extra = _read_yaml(Path(override_file))
        for key, value in _flatten(extra):
            _set_path(plain, key, value)
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
