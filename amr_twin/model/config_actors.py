"""The ``actors:`` section of the parameter file: the people and pallet jacks a world can hold.

Not the robot: the size, speed and turning of the things that move around it
(:mod:`amr_twin.model.actors` builds them, :mod:`amr_twin.sim.actors` moves them). A section
of settings (:attr:`~amr_twin.model.config_sections.Section.SETTINGS`): the robot's uncertainty
analysis never draws them. Each field's unit and allowed range is here; its value, source and
plausible range are in ``models/amr/amr.yaml``.
"""

from __future__ import annotations

from typing import ClassVar

from pydantic import model_validator

from amr_twin.model.config_sections import P, Section


class _Moving(Section):
    SETTINGS: ClassVar[bool] = True
    speed_m_s: float = P(unit="m/s", gt=0.0, le=3.0)
    speed_min_m_s: float = P(unit="m/s", gt=0.0, le=3.0)
    speed_max_m_s: float = P(unit="m/s", gt=0.0, le=3.0)
    turn_rate_rad_s: float = P(unit="rad/s", gt=0.1, le=10.0)
    give_way_s: float = P(unit="s", gt=0.0, le=600.0)
    touch_m: float = P(unit="m", ge=0.0, le=0.01)
    contact_timeconst_s: float = P(unit="s", ge=0.002, le=0.2)

    @model_validator(mode="after")
    def _speeds_ordered(self) -> "_Moving":
        if not self.speed_min_m_s <= self.speed_m_s <= self.speed_max_m_s:
            raise ValueError("actors.*: speed_min_m_s <= speed_m_s <= speed_max_m_s must hold")
        return self


class PersonCfg(_Moving):
    """A walking adult: two legs (vertical cylinders, what a 0.45 m scan plane cuts), torso and
    head."""

    height_m: float = P(unit="m", ge=1.0, le=2.2)
    leg_radius_m: float = P(unit="m", ge=0.02, le=0.12)
    leg_spacing_m: float = P(unit="m", ge=0.05, le=0.5)
    leg_length_m: float = P(unit="m", ge=0.5, le=1.1)
    torso_width_m: float = P(unit="m", ge=0.2, le=0.7)
    torso_depth_m: float = P(unit="m", ge=0.1, le=0.5)

    @model_validator(mode="after")
    def _fits(self) -> "PersonCfg":
        if self.leg_spacing_m < 2 * self.leg_radius_m:
            raise ValueError(
                "actors.person.leg_spacing_m: must be >= 2 x leg_radius_m (the legs would overlap)"
            )
        if self.leg_length_m > self.height_m - 0.3:
            raise ValueError(
                "actors.person.leg_length_m: must leave at least 0.3 m of height_m for torso and "
                "head"
            )
        return self


class PalletJackCfg(_Moving):
    """A manual pallet jack, forks lowered: two forks, the steer frame, the pump, the handle."""

    length_m: float = P(unit="m", ge=1.0, le=2.0)
    width_m: float = P(unit="m", ge=0.4, le=0.8)
    fork_length_m: float = P(unit="m", ge=0.6, le=1.6)
    fork_width_m: float = P(unit="m", ge=0.1, le=0.25)
    fork_height_m: float = P(unit="m", ge=0.05, le=0.12)
    frame_height_m: float = P(unit="m", ge=0.1, le=0.4)
    pump_radius_m: float = P(unit="m", ge=0.04, le=0.2)
    pump_height_m: float = P(unit="m", ge=0.3, le=0.8)
    handle_height_m: float = P(unit="m", ge=0.8, le=1.5)

    @model_validator(mode="after")
    def _fits(self) -> "PalletJackCfg":
        if self.fork_length_m >= self.length_m - 2 * self.pump_radius_m:
            raise ValueError(
                "actors.pallet_jack.fork_length_m: must leave room for the pump "
                "(< length_m - 2 x pump_radius_m)"
            )
        if 2 * self.fork_width_m > self.width_m:
            raise ValueError("actors.pallet_jack.fork_width_m: two forks must fit in width_m")
        if not self.fork_height_m < self.frame_height_m < self.pump_height_m < self.handle_height_m:
            raise ValueError(
                "actors.pallet_jack: fork_height_m < frame_height_m < pump_height_m < "
                "handle_height_m "
                "must hold"
            )
        return self


class ActorsCfg(Section):
    """The kinds of actor (``amr_twin.model.actors.KINDS``)."""

    SETTINGS: ClassVar[bool] = True
    person: PersonCfg
    pallet_jack: PalletJackCfg
