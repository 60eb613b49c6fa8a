"""The section classes of the parameter schema: one frozen pydantic model per YAML section.

Each field is declared with :func:`P`, which carries its unit (checked against the
file's ``unit:`` when loading) and its allowed range; cross-field checks are
``model_validator``s that raise a one-line message naming the field. The sections
are assembled into :class:`amr_twin.model.config.TwinConfig`, which also loads them.

Robot body and drive: :class:`SimCfg`, :class:`ChassisCfg`, :class:`DeckCfg`,
:class:`ComponentsCfg`, :class:`WheelCfg`, :class:`CasterCfg`, :class:`PayloadCfg`,
:class:`MotorCfg`, :class:`DriverCfg`, :class:`BatteryCfg`; the sensors' sections in
:mod:`.config_sensors`, the estimators' in :mod:`.config_estimation`.
"""

from __future__ import annotations

from typing import Annotated, Any, ClassVar, Iterator

from pydantic import BaseModel, ConfigDict, Field, model_validator


def P(
    default: Any = ...,
    *,
    unit: str,
    ge: float | None = None,
    le: float | None = None,
    gt: float | None = None,
    lt: float | None = None,
    setting: bool = False,
) -> Any:
    """A physical parameter field: its unit and range travel with the schema.

    ``setting``: a value the user or the twin chooses (a time step, a sensor mode, a filter's
    tuning), not a property of the robot measured with some uncertainty: never drawn by
    :mod:`amr_twin.calibration.uncertainty`.
    """
    extra: dict[str, Any] = {"unit": unit}
    if setting:
        extra["setting"] = True
    return Field(default, ge=ge, le=le, gt=gt, lt=lt, json_schema_extra=extra)


class Section(BaseModel):
    """Base of a parameter section: frozen, no unknown key, no inf or NaN.

    ``SETTINGS = True`` on a section marks all its fields as settings (see :func:`P`).
    """

    model_config = ConfigDict(frozen=True, extra="forbid", allow_inf_nan=False)
    SETTINGS: ClassVar[bool] = False


Vec3 = tuple[float, float, float]
_NonNeg = Annotated[float, Field(ge=0.0)]
_Pos = Annotated[float, Field(gt=0.0)]
NonNegVec3 = tuple[_NonNeg, _NonNeg, _NonNeg]
PosVec3 = tuple[_Pos, _Pos, _Pos]


class SimCfg(Section):
    timestep_s: float = P(unit="s", ge=2e-4, le=0.002, setting=True)
    floor_friction: float = P(unit="1", ge=0.05, le=2.0)
    floor_friction_field: bool = P(unit="bool", setting=True)
    floor_friction_low: float = P(unit="1", ge=0.05, le=2.0)
    floor_patch_m: float = P(unit="m", ge=0.1, le=4.0)
    gravity_m_s2: float = P(unit="m/s^2", ge=0.0, le=20.0)


class ChassisCfg(Section):
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
            raise ValueError(
                "chassis.floor_*_z_m: floor_a_z_m < floor_b_z_m < floor_c_z_m must hold"
            )
        if self.tube_wall_m * 2 >= self.tube_outer_m:
            raise ValueError("chassis.tube_wall_m: must be less than half of tube_outer_m")
        return self


class DeckCfg(Section):
    thickness_m: float = P(unit="m", ge=0.001, le=0.02)
    density_kg_m3: float = P(unit="kg/m^3", ge=2000, le=3000)


class ComponentCfg(Section):
    mass_kg: float = P(unit="kg", ge=0.0, le=50.0)
    size_m: NonNegVec3 = P(unit="m")
    pos_m: Vec3 = P(unit="m")


class ComponentsCfg(Section):
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


class WheelCfg(Section):
    radius_m: float = P(unit="m", ge=0.05, le=0.3)
    width_m: float = P(unit="m", ge=0.01, le=0.15)
    separation_m: float = P(unit="m", ge=0.2, le=1.0)
    mass_kg: float = P(unit="kg", gt=0.1, le=20.0)
    rotor_fraction: float = P(unit="1", ge=0.1, le=1.0)
    friction: float = P(unit="1", ge=0.1, le=2.0)
    tyre_stiffness_n_m: float = P(unit="N/m", ge=1e4, le=1e6)
    tyre_damping_n_s_m: float = P(unit="N*s/m", ge=0.0, le=1e4)
    rolling_resistance: float = P(unit="1", ge=0.0, le=0.1)
    tyre_slip: bool = P(unit="bool", setting=True)
    cornering_stiffness_per_n: float = P(unit="1/rad", ge=0.5, le=50.0)
    slip_stiffness_per_n: float = P(unit="1", ge=0.5, le=50.0)
    relaxation_length_lateral_m: float = P(unit="m", ge=0.005, le=0.5)
    relaxation_length_longitudinal_m: float = P(unit="m", ge=0.005, le=0.5)
    tyre_crown_radius_m: float = P(unit="m", ge=0.003, le=0.1)
    tyre_loss_time_s: float = P(unit="s", ge=0.0, le=0.05)
    radius_error_left_m: float = P(unit="m", ge=-0.01, le=0.01)
    radius_error_right_m: float = P(unit="m", ge=-0.01, le=0.01)
    separation_error_m: float = P(unit="m", ge=-0.05, le=0.05)
    radius_tolerance_m: float = P(unit="m", ge=0.0, le=0.005, setting=True)
    separation_tolerance_m: float = P(unit="m", ge=0.0, le=0.02, setting=True)
    hall_misalignment_sigma_deg: float = P(unit="deg", ge=0.0, le=2.0, setting=True)
    hall_jitter_us: float = P(unit="us", ge=0.0, le=100.0, setting=True)
    hall_hysteresis_deg: float = P(unit="deg", ge=0.0, le=2.0)
    hall_pole_pairs: int = P(unit="1", ge=1, le=60)

    @property
    def sc_edges_per_rev(self) -> int:
        """SC state changes per wheel revolution: three hall sensors, each toggling twice per pole
        pair."""
        return 6 * self.hall_pole_pairs

    def radius_of(self, side: str) -> float:
        """The ``left`` or ``right`` tyre's true rolling radius, m: ``radius_m`` plus its error."""
        return self.radius_m + (
            self.radius_error_left_m if side == "left" else self.radius_error_right_m
        )


class CasterCfg(Section):
    ball_diameter_m: float = P(unit="m", ge=0.01, le=0.12)
    x_m: float = P(unit="m", ge=0.1, le=0.7)
    y_m: float = P(unit="m", ge=0.05, le=0.3)
    stiffness_n_m: float = P(unit="N/m", ge=100.0, le=1e6)
    damping_n_s_m: float = P(unit="N*s/m", ge=1.0, le=1e5)
    preload_n: float = P(unit="N", ge=0.0, le=500.0)
    travel_m: float = P(unit="m", ge=0.001, le=0.05)
    mass_kg: float = P(unit="kg", gt=0.0, le=2.0)
    drop_m: float = P(unit="m", ge=-0.01, le=0.01)
    rolling_resistance: float = P(unit="1", ge=0.0, le=0.1)


class PayloadCfg(Section):
    """The payload box: set per run (``--payload-kg``, the sweep's points)."""

    SETTINGS: ClassVar[bool] = True
    mass_kg: float = P(unit="kg", ge=0.0, le=200.0)
    size_m: PosVec3 = P(unit="m")
    xy_m: tuple[float, float] = P(unit="m")
    max_mass_kg: float = P(unit="kg", gt=0.0, le=200.0, setting=True)
    handling_time_s: float = P(unit="s", ge=0.0, le=600.0, setting=True)


class MotorCfg(Section):
    ke_v_s_rad: float = P(unit="V*s/rad", gt=0.05, le=3.0)
    resistance_ohm: float = P(unit="ohm", gt=0.01, le=10.0)
    current_limit_a: float = P(unit="A", gt=0.5, le=60.0)
    friction_nm: float = P(unit="N*m", ge=0.0, le=5.0)
    damping_nm_s_rad: float = P(unit="N*m*s/rad", ge=0.0, le=5.0)


class DriverBoardCfg(Section):
    """One ZS-X11D1 board (one per wheel): what differs from board to board."""

    gain: float = P(unit="1", gt=0.1, le=20.0)


class DriverCfg(Section):
    """What the two ZS-X11D1 boards share (the model's ratings)."""

    deadband_duty: float = P(unit="1", ge=0.0, le=0.5)
    brake_current_limit_a: float = P(unit="A", gt=0.5, le=500.0)
    continuous_current_a: float = P(unit="A", gt=0.5, le=100.0)
    quiescent_current_a: float = P(unit="A", ge=0.0, le=1.0)


class BatteryCfg(Section):
    capacity_ah: float = P(unit="A*h", gt=0.1, le=200.0)
    v_full_v: float = P(unit="V", gt=1.0, le=100.0)
    v_nominal_v: float = P(unit="V", gt=1.0, le=100.0)
    v_empty_v: float = P(unit="V", gt=1.0, le=100.0)
    internal_resistance_ohm: float = P(unit="ohm", ge=0.0, le=2.0)
    soc_initial: float = P(unit="1", ge=0.0, le=1.0)
    auxiliary_power_w: float = P(unit="W", ge=0.0, le=500.0)
    charge_current_a: float = P(unit="A", gt=0.0, le=100.0)

    @model_validator(mode="after")
    def _voltages_ordered(self) -> "BatteryCfg":
        if not self.v_empty_v < self.v_nominal_v < self.v_full_v:
            raise ValueError("battery.v_*_v: v_empty_v < v_nominal_v < v_full_v must hold")
        return self
