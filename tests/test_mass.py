"""Mass properties from the parametric geometry (trimesh, no mujoco)."""

import numpy as np
import pytest

from amr_twin import mass
from amr_twin.config import load_config


def test_frame_mass_matches_tube_formula():
    cfg = load_config()
    c = cfg.chassis
    area = c.tube_outer_m ** 2 - (c.tube_outer_m - 2 * c.tube_wall_m) ** 2
    length = sum(max(ext) for _, _, ext, _ in mass.frame_members(cfg))
    expected = area * length * c.steel_density_kg_m3
    assert mass.frame_inertial(cfg).mass_kg == pytest.approx(expected, rel=1e-9)


def test_chassis_mass_is_sum_of_parts():
    cfg = load_config()
    parts = mass.frame_inertial(cfg).mass_kg
    parts += sum(np.prod(ext) * rho for _, _, ext, rho in mass.plates(cfg))
    parts += sum(comp.mass_kg for _, comp in cfg.components.items())
    parts += 2 * cfg.wheel.mass_kg * (1 - cfg.wheel.rotor_fraction)
    assert mass.chassis_inertial(cfg).mass_kg == pytest.approx(parts, rel=1e-9)


def test_combine_parallel_axis():
    a = mass.Inertial(1.0, np.array([1.0, 0, 0]), np.zeros((3, 3)))
    b = mass.Inertial(1.0, np.array([-1.0, 0, 0]), np.zeros((3, 3)))
    both = mass.combine([a, b])
    assert both.com_m == pytest.approx([0, 0, 0])
    assert both.inertia_kg_m2[1, 1] == pytest.approx(2.0)
    assert both.inertia_kg_m2[0, 0] == pytest.approx(0.0)


def test_wheel_inertia_about_axle():
    cfg = load_config()
    w = mass.wheel_inertial(cfg)
    m = cfg.wheel.mass_kg * cfg.wheel.rotor_fraction
    assert w.inertia_kg_m2[1, 1] == pytest.approx(0.5 * m * cfg.wheel.radius_m ** 2, rel=1e-3)
    assert w.inertia_kg_m2[0, 0] < w.inertia_kg_m2[1, 1]
