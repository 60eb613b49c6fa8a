"""The brush tyres' explicit states against the physics timestep: stability number and guard.

Reasons and measurements: docs/explanation/tyres.md#amr_twinmodeltyre_stability."""

from __future__ import annotations

import math
from dataclasses import dataclass

from amr_twin.model.config import TwinConfig
from amr_twin.model.urdf import BuildError

LOAD_MARGIN = 1.3
"""Dynamic load over static load a tyre is checked at: chapter 5's 60 deg/s turns about 1 m load the
outer wheel with up to 1.30 times its static load (measured, 20 and 50 kg payloads); straight
starts and reversals 1.03-1.13."""
S_MAX = 1.5
"""Largest stability number the guard lets run: the update is stable below 2 + a/2 (>= 2) and
measured stable up to 1.94; 1.5 keeps a quarter of that in hand (the chassis' coupling, the
spread of the load and of the wheel's inertia)."""
MAX_HALVINGS = 6
"""At most 64 steps where one was configured."""

_announced: set = set()  # the messages this process has written to stderr


class TyreTimestepError(BuildError):
    """The tyres need a timestep the loop cannot keep (one line: the parameters and S; a
    :class:`~amr_twin.model.urdf.BuildError`, so the CLI exits 2 and a sweep records it on the
    point)."""


@dataclass(frozen=True)
class TyreTimestep:
    """The guard's decision for one configuration.

    ``configured_s``: ``sim.timestep_s``; ``timestep_s``: the physics timestep the twin steps at
    (``configured_s / 2**halvings``); ``load_n``: the static load of each tyre (left, right), N;
    ``s_configured`` / ``s``: each tyre's stability number at ``LOAD_MARGIN`` times its load, at
    the configured and at the chosen timestep; ``s_max``: :data:`S_MAX`."""

    configured_s: float
    timestep_s: float
    halvings: int
    load_n: tuple[float, float]
    s_configured: tuple[float, float]
    s: tuple[float, float]
    s_max: float = S_MAX

    @property
    def steps_per_configured_step(self) -> int:
        """Physics steps the twin takes where ``sim.timestep_s`` would take one."""
        return 2**self.halvings

    def as_dict(self) -> dict:
        """The run summary's / metrics' record (only written when the timestep was halved)."""
        return {
            "configured_timestep_s": self.configured_s,
            "timestep_s": self.timestep_s,
            "halvings": self.halvings,
            "static_load_n": [round(v, 3) for v in self.load_n],
            "load_margin": LOAD_MARGIN,
            "stability_number_configured": [round(v, 4) for v in self.s_configured],
            "stability_number": [round(v, 4) for v in self.s],
            "stability_limit": self.s_max,
        }

    def message(self) -> str:
        """One line for stderr."""
        return (
            f"tyres: stability number S = {max(self.s_configured):.2f} > {self.s_max:g} at "
            f"sim.timestep_s = {self.configured_s * 1e3:g} ms (static tyre load "
            f"{max(self.load_n):.0f} N "
            f"x {LOAD_MARGIN:g}); physics timestep halved to {self.timestep_s * 1e3:g} ms "
            f"(S = {max(self.s):.2f}; docs/explanation/tyres.md)"
        )


def announce(step: TyreTimestep) -> None:
    """Write ``step``'s message to stderr, once a process for each configuration that was halved."""
    import sys

    if step.halvings and step.message() not in _announced:
        _announced.add(step.message())
        print(step.message(), file=sys.stderr)


def rotating_mass_kg(cfg: TwinConfig) -> float:
    """``J / r^2``: the wheel's rotating inertia about its axle over the radius squared, kg."""
    from amr_twin.model.mass import wheel_inertial

    return float(wheel_inertial(cfg).inertia_kg_m2[1, 1]) / cfg.wheel.radius_m**2


def stability_number(
    k_x_n_m: float, loss_time_s: float, timestep_s: float, mass_kg: float
) -> float:
    """``S = (k_x dt + tau k_x) dt / M`` (module docstring), dimensionless."""
    return (k_x_n_m * timestep_s + loss_time_s * k_x_n_m) * timestep_s / mass_kg


def tyre_timestep(cfg: TwinConfig) -> TyreTimestep:
    """The guard's decision for ``cfg`` (its timestep unchanged without the brush tyres)."""
    dt0 = float(cfg.sim.timestep_s)
    if not cfg.wheel.tyre_slip:
        return TyreTimestep(dt0, dt0, 0, (0.0, 0.0), (0.0, 0.0), (0.0, 0.0))
    from amr_twin.model.statics import solve

    w = cfg.wheel
    loads = solve(cfg).loads_n
    load = (float(loads["wheel_left"]), float(loads["wheel_right"]))
    mass = rotating_mass_kg(cfg)

    def numbers(dt: float) -> tuple[float, float]:
        return tuple(
            stability_number(
                w.slip_stiffness_per_n * LOAD_MARGIN * n / w.relaxation_length_longitudinal_m,
                w.tyre_loss_time_s,
                dt,
                mass,
            )
            for n in load
        )

    first = numbers(dt0)
    halvings, dt, s = 0, dt0, first
    while max(s) >= S_MAX:
        halvings += 1
        dt = dt0 / 2**halvings
        s = numbers(dt)
        if halvings > MAX_HALVINGS or abs(dt * 1e6 - round(dt * 1e6)) > 1e-6:
            raise TyreTimestepError(
                f"sim.timestep_s: {dt0:g} s cannot be halved far enough for the tyres "
                f"(wheel.slip_stiffness_per_n "
                f"{w.slip_stiffness_per_n:g}, wheel.relaxation_length_longitudinal_m "
                f"{w.relaxation_length_longitudinal_m:g}, wheel.tyre_loss_time_s "
                f"{w.tyre_loss_time_s:g}, static "
                f"load {max(load):.0f} N: S = {max(first):.2f}, allowed < {S_MAX:g}) on whole "
                f"microseconds; "
                f"set sim.timestep_s to "
                f"{_largest_stable_us(max(load) * LOAD_MARGIN, cfg, mass) / 1e6:g} or less"
            )
    return TyreTimestep(dt0, dt, halvings, load, first, s)


def _largest_stable_us(load_n: float, cfg: TwinConfig, mass_kg: float) -> int:
    """The largest whole-microsecond timestep at which a tyre under ``load_n`` has S below S_MAX."""
    w = cfg.wheel
    k = w.slip_stiffness_per_n * load_n / w.relaxation_length_longitudinal_m
    c = w.tyre_loss_time_s * k
    dt = (-c + math.sqrt(c * c + 4.0 * k * S_MAX * mass_kg)) / (2.0 * k)  # k dt^2 + c dt = S_MAX M
    return max(1, math.floor(dt * 1e6 * (1.0 - 1e-9)))
