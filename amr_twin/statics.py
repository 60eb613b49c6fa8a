"""Static description of a built robot: mass, support loads, tip margin.

The loads are measured in the settled simulation (motors braked, 1.5 s), not
computed from a formula: they are what the contact solver gives.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import ConvexHull

from .build import build
from .config import TwinConfig
from .physics import Physics

CONTACT_MIN_N = 0.5
"""A support carrying less than this is counted as lifted off."""


def tip_margin_m(points_xy: np.ndarray, com_xy: np.ndarray) -> float:
    """Signed distance from ``com_xy`` to the nearest edge of the support polygon.

    Parameters
    ----------
    points_xy : (n, 2) support points in contact, m.
    com_xy : (2,) ground projection of the centre of mass, m.

    Returns
    -------
    float : positive inside the polygon, negative outside, m.
    """
    points_xy = np.asarray(points_xy, float)
    if len(points_xy) < 3:
        return -float("inf")
    hull = ConvexHull(points_xy)
    # equations: outward normal n and offset c with n.p + c <= 0 inside
    return float(np.min(-(hull.equations[:, :2] @ com_xy + hull.equations[:, 2])))


def settled_physics(cfg: TwinConfig, settle_s: float = 1.5) -> Physics:
    """Build the robot in an empty world and let it settle."""
    physics = Physics(build(cfg, world="empty").model)
    physics.settle(settle_s)
    return physics


def describe(cfg: TwinConfig) -> dict:
    """The ``amr-twin model --json`` object."""
    physics = settled_physics(cfg)
    loads = physics.support_loads_n()
    points = physics.support_points_xy()
    in_contact = np.array([points[k] for k, f in loads.items() if f > CONTACT_MIN_N])
    com = physics.com_world_m()
    total = physics.robot_mass_kg()
    return {
        "total_mass_kg": round(total, 4),
        "payload_kg": cfg.payload.mass_kg,
        "payload_xy_m": list(cfg.payload.xy_m),
        "wheel_radius_m": cfg.wheel.radius_m,
        "wheel_separation_m": cfg.wheel.separation_m,
        "caster_count": 4,
        "static_load_n": {k: round(v, 3) for k, v in loads.items()},
        "static_load_sum_n": round(sum(loads.values()), 3),
        "weight_n": round(total * cfg.sim.gravity_m_s2, 3),
        "com_m": [round(float(v), 5) for v in com],
        "tip_margin_m": round(tip_margin_m(in_contact, com[:2]), 5),
        "timestep_s": cfg.sim.timestep_s,
    }
