"""A payload sweep point's result as typed records, and its flat JSON row written from them.

:func:`amr_twin.experiments.payload.simulation.simulate_point` returns a :class:`PointResult`:
the point (mass, position, command, the parameter draw), the statics (:class:`Statics`), the run
(:class:`Dynamics`: the supports' least loads, the least loaded wheel's moment
(:class:`MinWheel`), the electrics (:class:`Electrics`), each wheel's step (:class:`WheelRun`)) and
the verdict. :meth:`PointResult.as_json` is the row of ``runs/<key>.json`` and ``sweep.csv``:
flat, the parts a point did not reach (an invalid position, a refused command, a diverged run)
left out, non-finite numbers as null. Loads in N, speeds in RPM (signed as the reference), times
in seconds after the command.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from typing import Optional


@dataclass(frozen=True)
class Statics:
    """The loaded robot at rest (:func:`amr_twin.model.statics.describe`): total mass kg, tip margin
    m, the least caster load N, the supports under CONTACT_MIN_N (``;``-joined) and each support's
    load N (``wheel_left`` ... ``caster_rear_right``)."""

    total_mass_kg: float
    tip_margin_m: float
    min_caster_n: float
    lifted: str
    loads_n: dict[str, float]

    def row(self) -> dict:
        return {
            "total_mass_kg": self.total_mass_kg,
            "static_tip_margin_m": self.tip_margin_m,
            "static_min_caster_n": self.min_caster_n,
            "static_lifted": self.lifted,
            **{f"static_{k}_n": v for k, v in self.loads_n.items()},
        }


@dataclass(frozen=True)
class MinWheel:
    """The moment a drive wheel was least loaded: which, when (s), the body-frame acceleration
    (ax, ay) m/s^2 then, the quasi-static load it gives N, and the mechanism in words."""

    wheel: str
    t_s: float
    accel_m_s2: list[float]
    quasi_static_n: float
    mechanism: str

    def row(self) -> dict:
        return {
            f"dyn_min_wheel{'' if k == 'wheel' else '_' + k}": v for k, v in asdict(self).items()
        }


@dataclass(frozen=True)
class Electrics:
    """Over the last quarter of the run: each motor's mean |current| A (left, right) and the
    battery's mean current A; over the run: energy drawn J, distance m, J/m (None under 5 cm)."""

    steady_current_a: tuple[float, float]
    battery_steady_a: float
    energy_j: float
    distance_m: float
    energy_j_per_m: Optional[float]

    def row(self) -> dict:
        return {
            "left_steady_current_a": self.steady_current_a[0],
            "right_steady_current_a": self.steady_current_a[1],
            "battery_steady_a": self.battery_steady_a,
            "energy_j": self.energy_j,
            "distance_m": self.distance_m,
            "energy_j_per_m": self.energy_j_per_m,
        }


@dataclass(frozen=True)
class WheelRun:
    """One wheel of the run: its signed reference RPM and largest |slip| m/s; with a reference, the
    step of its published speed (``step``: delay_s, rise_s, peak_s, settling_s, overshoot_rpm,
    steady_error_rpm, oscillation_rpm; None when nothing was published) and its steady state
    (``steady``: true_steady_error_rpm, steady_duty, open_loop_duty, steady_slip_ratio)."""

    name: str
    reference_rpm: float
    max_slip_m_s: float
    step: Optional[dict[str, Optional[float]]] = None
    steady: Optional[dict[str, float]] = None

    def row(self) -> dict:
        out = {
            f"{self.name}_reference_rpm": self.reference_rpm,
            f"{self.name}_max_slip_m_s": self.max_slip_m_s,
        }
        for part in (self.step, self.steady):
            out.update({f"{self.name}_{k}": v for k, v in (part or {}).items()})
        return out


@dataclass(frozen=True)
class Dynamics:
    """The run: the largest tilt deg, the least wheel and caster spring loads N, the supports that
    lost contact, the least wheel contact force N (chatter included), the least loaded moment, the
    electrics, whether a wheel lifted, each wheel, whether every driven wheel tracked, and the
    physics timestep s where the tyres' guard halved it (:mod:`amr_twin.model.tyre_stability`; else
    None, not written)."""

    max_tilt_deg: float
    min_wheel_n: float
    min_caster_n: float
    lifted: str
    min_wheel_contact_n: float
    min_wheel: MinWheel
    electrics: Electrics
    wheel_lift_off: bool
    wheels: tuple[WheelRun, ...]
    tracks: bool
    tyre_timestep_s: Optional[float] = (
        None  # the physics timestep when the tyres' guard halved it, s
    )

    def row(self) -> dict:
        out = {
            "max_tilt_deg": self.max_tilt_deg,
            "dyn_min_wheel_n": self.min_wheel_n,
            "dyn_min_caster_n": self.min_caster_n,
            "dyn_lifted": self.lifted,
            "dyn_min_wheel_contact_n": self.min_wheel_contact_n,
            **self.min_wheel.row(),
            **self.electrics.row(),
            "wheel_lift_off": self.wheel_lift_off,
        }
        for wheel in self.wheels:
            out.update(wheel.row())
        out["tracks"] = self.tracks
        if self.tyre_timestep_s is not None:
            out["tyre_timestep_s"] = self.tyre_timestep_s
        return out


@dataclass
class PointResult:
    """One sweep point: its key and fingerprint (:class:`amr_twin.experiments.payload.point.Point`),
    mass kg, position, command, whether the position is valid, the error that stopped it (""
    without), the parameter draw (``sample``, ``sample_id``; None for the nominal parameters), the
    payload's position (x, y) m, the statics and the run (None where not reached), the driver's
    continuous current rating A it is judged by, whether a motor exceeded it, the verdict and its
    wall time s."""

    key: str
    fingerprint: str
    mass_kg: float
    position: str
    command: str
    valid: bool = True
    error: str = ""
    sample: Optional[int] = None
    sample_id: Optional[str] = None
    xy_m: Optional[tuple[float, float]] = None
    statics: Optional[Statics] = None
    dynamics: Optional[Dynamics] = None
    current_limit_a: Optional[float] = None
    motor_overload: Optional[bool] = None
    safe: bool = False
    wall_s: Optional[float] = None

    def as_json(self) -> dict:
        """The flat row (JSON-ready: non-finite numbers as None)."""
        row = {
            "key": self.key,
            "fingerprint": self.fingerprint,
            "mass_kg": self.mass_kg,
            "position": self.position,
            "command": self.command,
            "valid": self.valid,
            "error": self.error,
        }
        if self.sample is not None:
            row.update(sample=self.sample, sample_id=self.sample_id)
        if self.xy_m is not None:
            row.update(x_m=self.xy_m[0], y_m=self.xy_m[1])
        for part in (self.statics, self.dynamics):
            if part is not None:
                row.update(part.row())
        if self.current_limit_a is not None:
            row.update(current_limit_a=self.current_limit_a, motor_overload=self.motor_overload)
        row["safe"] = self.safe
        if self.wall_s is not None:
            row["wall_s"] = self.wall_s
        return {
            k: (None if isinstance(v, float) and not math.isfinite(v) else v)
            for k, v in row.items()
        }
