"""Statics of the robot standing on a level floor: support loads from its compliances.

A hand calculation, independent of MuJoCo (the tests check it against a free
settle of the exported MJCF). The chassis is rigid; it stands on six supports:

- two tyres, radial springs ``k_t`` under the axle (``wheel.tyre_stiffness_n_m``):
  load ``k_t s`` for an overlap ``s > 0`` of the undeformed tyre with the floor, 0 when
  lifted;
- four spring-loaded ball casters at the deck corners: the ball at its lower stop
  reaches ``caster.drop_m`` below the unloaded tyres' plane. Pushed up by ``s > 0`` the
  spring gives ``P + k_c s`` (preload ``P``), plus the ball's weight; at ``s = 0`` the
  stop takes any load between 0 and that; at ``s = travel`` the spring is solid.

The chassis sinks by ``u`` and pitches and rolls by small angles, so support ``i`` at
``(x_i, y_i)`` overlaps the floor by ``s_i = d_i + u + theta x_i + phi y_i``. Vertical
force and the two moments balance the weight at the centre of mass, which the tilt
moves sideways by its height times the angle. The energy is
convex, so the solution is unique; each support's regime (lifted, at its stop,
sprung, solid) is found by trying the regimes until they are consistent.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass, replace

import numpy as np

from amr_twin.model.config import TwinConfig
from amr_twin.model.mass import robot_mass_com
from amr_twin.model.support_polygon import tip_margin_m

CONTACT_MIN_N = 0.5
"""A support carrying less than this is counted as lifted off."""

LIFTED, STOP, SPRUNG, SOLID = "lifted", "at stop", "sprung", "solid"
WHEEL_NAMES = ("wheel_left", "wheel_right")
CASTER_NAMES = ("caster_front_left", "caster_front_right", "caster_rear_left", "caster_rear_right")


@dataclass(frozen=True)
class Statics:
    """Solution of :func:`solve`. Loads in N, compressions in m, angles in rad."""

    loads_n: dict[str, float]  # floor reaction on each support
    regimes: dict[str, str]  # lifted, at stop, sprung or solid
    compression_m: dict[str, float]  # tyre deflection or caster spring travel from its stop
    points_xy_m: dict[str, np.ndarray]  # (2,) contact point in base_link
    sink_m: float  # chassis sink at the base_link origin
    pitch_rad: float  # nose down positive
    roll_rad: float  # left side down positive
    mass_kg: float
    com_m: np.ndarray  # (3,) robot with payload, base_link (standing unloaded)


def support_points_xy(cfg: TwinConfig) -> dict[str, np.ndarray]:
    """Contact point of each support with the floor, base_link xy, m."""
    half = cfg.wheel.separation_m / 2
    k = cfg.caster
    points = {"wheel_left": np.array([0.0, half]), "wheel_right": np.array([0.0, -half])}
    for name, (sx, sy) in zip(CASTER_NAMES, ((1, 1), (1, -1), (-1, 1), (-1, -1))):
        points[name] = np.array([sx * k.x_m, sy * k.y_m])
    return points


_solved: dict[tuple, Statics] = {}
SOLVED_KEPT = 16
"""Solutions kept (the last ones asked): a sweep point asks its robot's statics at rest once
for its row and once for each command's least-loaded instant (~0.8 ms a solve)."""


def solve(cfg: TwinConfig, accel_m_s2: tuple[float, float] = (0.0, 0.0)) -> Statics:
    """Support loads of the robot on a level floor (see the module docstring).

    ``accel_m_s2``: the robot's acceleration (x forward, y left, base_link), for the
    quasi-static loads of a robot that accelerates or turns: d'Alembert's force ``-m a``
    at the centre of mass moves the weight's line of action by ``-a z_com / g``.
    A solution asked again is the kept one, its dicts and arrays copied (the caller's own).
    """
    key = (cfg, float(accel_m_s2[0]), float(accel_m_s2[1]))
    st = _solved.pop(key, None)
    if st is None:
        st = _solve(cfg, accel_m_s2)
        if len(_solved) >= SOLVED_KEPT:
            del _solved[next(iter(_solved))]  # the least recently asked
    _solved[key] = st
    return replace(
        st,
        loads_n=dict(st.loads_n),
        regimes=dict(st.regimes),
        compression_m=dict(st.compression_m),
        points_xy_m={n: v.copy() for n, v in st.points_xy_m.items()},
        com_m=st.com_m.copy(),
    )


def _solve(cfg: TwinConfig, accel_m_s2: tuple[float, float]) -> Statics:
    from amr_twin.model import mass

    g = cfg.sim.gravity_m_s2
    m_kg, com = robot_mass_com(cfg)
    com = com.copy()
    com[:2] -= np.asarray(accel_m_s2, float) * com[2] / g
    weight = m_kg * g
    points = support_points_xy(cfg)
    k_t, k = cfg.wheel.tyre_stiffness_n_m, cfg.caster
    ball_n = mass.caster_inertial(cfg).mass_kg * g
    # per support: offset d (overlap at u = 0), stiffness, force at s = 0+ and travel
    spec = {name: (0.0, k_t, 0.0, math.inf) for name in WHEEL_NAMES}
    spec.update(
        {
            name: (k.drop_m, k.stiffness_n_m, k.preload_n + ball_n, k.travel_m)
            for name in CASTER_NAMES
        }
    )
    names = list(points)
    # the likely regimes first; a support exactly at its stop before a lifted one, so that a
    # degenerate case (several balls just touching) shares the load (least-norm forces)
    options = {
        name: ((SPRUNG, LIFTED) if name in WHEEL_NAMES else (SPRUNG, STOP, LIFTED, SOLID))
        for name in names
    }
    guesses = _active_set_guesses(names, points, spec, weight, com)
    for combo in itertools.chain(guesses, itertools.product(*(options[n] for n in names))):
        result = _try(dict(zip(names, combo)), names, points, spec, weight, com)
        if result is not None:
            x, forces, overlaps = result
            regimes = dict(zip(names, combo))
            compression = {n: max(0.0, overlaps[n]) for n in names}
            return Statics(
                loads_n=forces,
                regimes=regimes,
                compression_m=compression,
                points_xy_m=points,
                sink_m=float(x[0]),
                pitch_rad=float(x[1]),
                roll_rad=float(x[2]),
                mass_kg=m_kg,
                com_m=com,
            )
    raise ValueError("statics: the robot has no equilibrium on its supports (it tips over)")


def _active_set_guesses(names, points, spec, weight, com, iterations: int = 12):
    """Regime assignments from a few rounds of "solve, then move each support to the regime
    its overlap and force call for" (usually the answer; the caller checks it)."""
    regime = {n: SPRUNG for n in names}
    seen = []
    for _ in range(iterations):
        combo = tuple(regime[n] for n in names)
        if combo in seen:
            return
        seen.append(combo)
        yield combo
        x = _solve_unchecked(regime, names, points, spec, weight, com)
        if x is None:
            return
        fixed = [
            m for m in names if regime[m] in (STOP, SOLID)
        ]  # x's force unknowns, before this round's moves
        for n in names:
            d, stiff, f0, travel = spec[n]
            s_n = d + x[0] + x[1] * points[n][0] + x[2] * points[n][1]
            r = regime[n]
            if r in (STOP, SOLID):
                f = float(x[3 + fixed.index(n)])
                if r == STOP:
                    regime[n] = LIFTED if f < 0 else SPRUNG if f > f0 else STOP
                else:
                    regime[n] = SPRUNG if f < f0 + stiff * travel else SOLID
            elif s_n > travel:
                regime[n] = SOLID
            elif s_n > 0:
                regime[n] = SPRUNG if (r != LIFTED or n in WHEEL_NAMES) else STOP
            else:
                regime[n] = LIFTED if n in WHEEL_NAMES or f0 == 0 or r == LIFTED else STOP


def _solve_unchecked(regime, names, points, spec, weight, com):
    a, b = _system(regime, names, points, spec, weight, com)
    x = np.linalg.lstsq(a, b, rcond=None)[0]
    return x if np.all(np.isfinite(x)) else None


def _system(regime, names, points, spec, weight, com):
    """The linear system of one regime assignment: unknowns u, theta, phi, then one
    force per support held at a stop or solid."""
    fixed = [n for n in names if regime[n] in (STOP, SOLID)]
    size = 3 + len(fixed)
    a = np.zeros((size, size))
    b = np.zeros(size)
    b[:3] = weight * np.array([1.0, com[0], com[1]])
    # tilting moves the centre of mass sideways by its height times the angle
    a[1, 1] -= weight * com[2]
    a[2, 2] -= weight * com[2]
    for n in names:
        x, y = points[n]
        arm = np.array([1.0, x, y])  # force, moment about y (x F), moment about x (y F)
        d, stiff, f0, travel = spec[n]
        if regime[n] == SPRUNG:  # F = f0 + stiff (d + u + theta x + phi y)
            a[:3, :3] += np.outer(arm, stiff * arm)
            b[:3] -= arm * (f0 + stiff * d)
        elif regime[n] in (STOP, SOLID):
            j = 3 + fixed.index(n)
            a[:3, j] += arm  # unknown force
            a[j, :3] = arm  # overlap fixed: d + u + theta x + phi y = s_fixed
            b[j] = (0.0 if regime[n] == STOP else travel) - d
    return a, b


def _try(regime: dict[str, str], names, points, spec, weight: float, com: np.ndarray):
    """Solve the linear system of one regime assignment; None if it is inconsistent."""
    fixed = [n for n in names if regime[n] in (STOP, SOLID)]
    a, b = _system(regime, names, points, spec, weight, com)
    x = np.linalg.lstsq(a, b, rcond=None)[0]  # least-norm forces where the stops are redundant
    if not np.all(np.isfinite(x)) or not np.allclose(
        a @ x, b, rtol=1e-9, atol=1e-9 * max(1.0, weight)
    ):
        return None
    if not _stable(a[:3, :3], a[3:, :3]):
        return None
    forces, overlaps = {}, {}
    tol = 1e-12
    for n in names:
        px, py = points[n]
        d, stiff, f0, travel = spec[n]
        s = d + x[0] + x[1] * px + x[2] * py
        overlaps[n] = s
        r = regime[n]
        if r == LIFTED:
            if s > tol:
                return None
            forces[n] = 0.0
        elif r == SPRUNG:
            if s < -tol or s > travel + tol:
                return None
            forces[n] = f0 + stiff * s
        else:
            f = float(x[3 + fixed.index(n)])
            limit_lo = 0.0 if r == STOP else f0 + stiff * travel
            limit_hi = f0 if r == STOP else math.inf
            if f < limit_lo - 1e-9 or f > limit_hi + 1e-9:
                return None
            forces[n] = f
    return x, forces, overlaps


def _stable(stiffness: np.ndarray, fixed_arms: np.ndarray) -> bool:
    """Is the equilibrium a minimum of the energy? (3, 3) stiffness of the sprung supports
    and the weight's tilt term, restricted to the motions the fixed supports allow."""
    if len(fixed_arms):
        _, sv, vt = np.linalg.svd(fixed_arms)
        rank = int(np.sum(sv > 1e-9 * max(1.0, sv.max())))
        free = vt[rank:].T
    else:
        free = np.eye(3)
    if free.shape[1] == 0:
        return True
    reduced = free.T @ (0.5 * (stiffness + stiffness.T)) @ free
    return bool(np.all(np.linalg.eigvalsh(reduced) > 0))


def describe(cfg: TwinConfig) -> dict:
    """The ``amr-twin model --json`` object."""
    st = solve(cfg)
    in_contact = np.array([st.points_xy_m[n] for n, f in st.loads_n.items() if f > CONTACT_MIN_N])
    return {
        "total_mass_kg": round(st.mass_kg, 4),
        "payload_kg": cfg.payload.mass_kg,
        "payload_xy_m": list(cfg.payload.xy_m),
        "wheel_radius_m": cfg.wheel.radius_m,
        "wheel_separation_m": cfg.wheel.separation_m,
        "caster_count": 4,
        "static_load_n": {k: round(v, 3) for k, v in st.loads_n.items()},
        "static_load_sum_n": round(sum(st.loads_n.values()), 3),
        "support_regime": dict(st.regimes),
        "support_compression_mm": {k: round(v * 1e3, 4) for k, v in st.compression_m.items()},
        "weight_n": round(st.mass_kg * cfg.sim.gravity_m_s2, 3),
        "com_m": [round(float(v), 5) for v in st.com_m],
        "tip_margin_m": round(tip_margin_m(in_contact, st.com_m[:2]), 5),
        "timestep_s": cfg.sim.timestep_s,
    }
