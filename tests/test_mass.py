"""Mass properties from the parametric geometry (trimesh, no mujoco)."""

import numpy as np
import pytest

from amr_twin import mass
from amr_twin.config import load_config


# Hand figures from amr.yaml (chassis 0.70 x 0.40 m, floors at 0.10 / 0.27 / 0.42 m,
# 20 x 20 x 1.5 mm AISI304 tube at 7930 kg/m^3):
#   rails: 3 floors x (2 sides x 0.70 + 3 cross rails x (0.40 - 2 x 0.02)) = 3 x 2.48 = 7.44 m
#   posts: 4 x (0.42 - (0.10 - 0.02)) = 1.36 m; tube section 0.02^2 - 0.017^2 = 1.11e-4 m^2
FRAME_KG = (7.44 + 1.36) * (0.02 ** 2 - 0.017 ** 2) * 7930  # 7.746 kg
PLATES_KG = 2 * 0.70 * 0.40 * 0.001 * 7930 + 0.70 * 0.40 * 0.003 * 2700  # steel (a), (c); aluminium deck (b)
COMPONENTS_KG = 5.0 + 0.6 + 1.2 + 0.9 + 0.4 + 0.17 + 0.01  # battery ... imu
STATORS_KG = 2 * 3.5 * (1 - 0.6)  # non-rotating share of the two hub motors
ROBOT_KG = FRAME_KG + PLATES_KG + COMPONENTS_KG + STATORS_KG + 2 * 3.5 * 0.6 + 4 * 0.15  # + rotors, casters


def test_frame_mass_is_the_hand_figure():
    assert mass.frame_inertial(load_config()).mass_kg == pytest.approx(FRAME_KG, rel=1e-9)
    assert FRAME_KG == pytest.approx(7.746, abs=1e-3)


def test_chassis_and_robot_masses_are_the_hand_figures():
    cfg = load_config()
    assert mass.chassis_inertial(cfg).mass_kg == pytest.approx(FRAME_KG + PLATES_KG + COMPONENTS_KG + STATORS_KG,
                                                             rel=1e-9)
    assert mass.robot_mass_kg(cfg) == pytest.approx(ROBOT_KG, rel=1e-9)
    assert ROBOT_KG == pytest.approx(30.335, abs=1e-3)


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
