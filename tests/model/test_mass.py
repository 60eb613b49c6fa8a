"""Mass properties from the parametric geometry (closed forms, checked against trimesh; no
mujoco)."""

import numpy as np
import pytest

from amr_twin.model import inertia, mass
from amr_twin.model.config import load_config


# Hand figures from amr.yaml (chassis 0.70 x 0.40 m, floors at 0.10 / 0.27 / 0.42 m,
# 20 x 20 x 1.5 mm AISI304 tube at 7930 kg/m^3):
#   rails: 3 floors x (2 sides x 0.70 + 3 cross rails x (0.40 - 2 x 0.02)) = 3 x 2.48 = 7.44 m
#   posts: 4 x (0.42 - (0.10 - 0.02)) = 1.36 m; tube section 0.02^2 - 0.017^2 = 1.11e-4 m^2
FRAME_KG = (7.44 + 1.36) * (0.02**2 - 0.017**2) * 7930  # 7.746 kg
PLATES_KG = (
    2 * 0.70 * 0.40 * 0.001 * 7930 + 0.70 * 0.40 * 0.003 * 2700
)  # steel (a), (c); aluminium deck (b)
COMPONENTS_KG = 5.0 + 0.6 + 1.2 + 0.9 + 0.4 + 0.17 + 0.01  # battery ... imu
STATORS_KG = 2 * 3.5 * (1 - 0.6)  # non-rotating share of the two hub motors
UWB_TAG_KG = 0.02  # the DWM1000 tag board on its own link (uwb_tag)
ROBOT_KG = (
    FRAME_KG + PLATES_KG + COMPONENTS_KG + STATORS_KG + 2 * 3.5 * 0.6 + 4 * 0.15
)  # + rotors, casters


def test_frame_mass_is_the_hand_figure():
    assert mass.frame_inertial(load_config()).mass_kg == pytest.approx(FRAME_KG, rel=1e-9)
    assert FRAME_KG == pytest.approx(7.746, abs=1e-3)


def test_chassis_and_robot_masses_are_the_hand_figures():
    cfg = load_config()
    on_links_kg = (
        0.17 + 0.01
    )  # the LiDAR and the IMU board ride on their own links (laser, imu_link)
    assert mass.chassis_inertial(cfg).mass_kg == pytest.approx(
        FRAME_KG + PLATES_KG + COMPONENTS_KG - on_links_kg + STATORS_KG, rel=1e-9
    )
    assert mass.robot_mass_kg(cfg) == pytest.approx(ROBOT_KG + UWB_TAG_KG, rel=1e-9)
    assert ROBOT_KG + UWB_TAG_KG == pytest.approx(30.355, abs=1e-3)


def test_sensor_links_carry_their_own_mass():
    cfg = load_config()
    links = mass.sensor_link_inertials(cfg)
    assert links["laser"].mass_kg == cfg.components.lidar.mass_kg
    assert links["imu_link"].mass_kg == cfg.components.imu.mass_kg
    assert links["uwb_tag"].mass_kg == cfg.uwb.tag_mass_kg
    lidar = cfg.components.lidar
    assert links["laser"].com_m[2] == pytest.approx(
        lidar.size_m[2] / 2 - 0.04
    )  # base 4 cm below the optics


def test_combine_parallel_axis():
    a = inertia.Inertial(1.0, np.array([1.0, 0, 0]), np.zeros((3, 3)))
    b = inertia.Inertial(1.0, np.array([-1.0, 0, 0]), np.zeros((3, 3)))
    both = inertia.combine([a, b])
    assert both.com_m == pytest.approx([0, 0, 0])
    assert both.inertia_kg_m2[1, 1] == pytest.approx(2.0)
    assert both.inertia_kg_m2[0, 0] == pytest.approx(0.0)


def test_wheel_inertia_about_axle():
    cfg = load_config()
    w = mass.wheel_inertial(cfg)
    m = cfg.wheel.mass_kg * cfg.wheel.rotor_fraction
    assert w.inertia_kg_m2[1, 1] == pytest.approx(0.5 * m * cfg.wheel.radius_m**2, rel=1e-3)
    assert w.inertia_kg_m2[0, 0] < w.inertia_kg_m2[1, 1]


def test_closed_forms_match_trimesh_meshes():
    """The closed forms against trimesh's mass properties of the same solids (an independent
    computation over triangles): boxes exactly, a fine cylinder and icosphere closely."""
    trimesh = pytest.importorskip("trimesh")
    for extents in ((0.7, 0.02, 0.02), (0.02, 0.36, 0.017), (0.7, 0.4, 0.003)):
        mesh = trimesh.creation.box(extents=extents)
        mesh.density = 7930.0
        part = mass._box(extents, (0.0, 0.0, 0.0), density=7930.0)
        assert part.mass_kg == pytest.approx(mesh.mass, rel=1e-12)
        np.testing.assert_allclose(part.inertia_kg_m2, mesh.moment_inertia, rtol=1e-12, atol=1e-18)
    cylinder = trimesh.creation.cylinder(radius=0.125, height=0.06, sections=4096)
    cylinder.density = 2.1 / cylinder.volume
    np.testing.assert_allclose(
        inertia.cylinder_inertia(0.125, 0.06, 2.1), cylinder.moment_inertia, rtol=1e-5, atol=1e-12
    )
    sphere = trimesh.creation.icosphere(subdivisions=5, radius=0.025)
    sphere.density = 0.15 / sphere.volume
    np.testing.assert_allclose(
        inertia.sphere_inertia(0.025, 0.15), sphere.moment_inertia, rtol=1e-3, atol=1e-12
    )


def test_chassis_inertia_against_trimesh_parts():
    """The whole chassis link (frame tubes, plates, components, stators) with every box made by
    trimesh instead: the same mass, centre of mass and inertia."""
    trimesh = pytest.importorskip("trimesh")

    def mesh_box(extents, center, mass_kg=None, density=None):
        mesh = trimesh.creation.box(extents=extents)
        mesh.density = density if density is not None else mass_kg / mesh.volume
        return inertia.Inertial(
            float(mesh.mass), np.asarray(center, float), np.asarray(mesh.moment_inertia)
        )

    cfg = load_config()
    closed = mass.chassis_inertial(cfg)
    original = mass._box
    try:
        mass._box = mesh_box
        meshed = mass.chassis_inertial(cfg)
    finally:
        mass._box = original
    assert closed.mass_kg == pytest.approx(meshed.mass_kg, rel=1e-12)
    np.testing.assert_allclose(closed.com_m, meshed.com_m, rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(closed.inertia_kg_m2, meshed.inertia_kg_m2, rtol=1e-10, atol=1e-14)


def test_mass_module_needs_no_mesh_library():
    """The model build's mass properties do not import trimesh (0.8 s of start-up)."""
    import subprocess
    import sys

    code = (
        "import sys, amr_twin.model.build, amr_twin.model.statics; print('trimesh' in sys.modules)"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False"


@pytest.mark.parametrize(
    "key, value, moves",
    [
        ("components.battery.mass_kg", 9.0, "mass"),
        ("deck.density_kg_m3", 2900.0, "mass"),
        ("chassis.tube_wall_m", 0.002, "mass"),
        ("wheel.radius_m", 0.14, "com"),
        ("caster.drop_m", 0.004, "com"),
        ("components.lidar.pos_m", [0.3, 0.0, 0.35], "com"),
        ("uwb.tag_mass_kg", 0.05, "mass"),
        ("payload.mass_kg", 20.0, "mass"),
    ],
)
def test_mass_and_com_follow_every_section_they_are_built_from(key, value, moves):
    """robot_mass_com keeps the robot per robot and payload: a change of any section it reads
    shows."""
    base_mass, base_com = mass.robot_mass_com(load_config())
    mass_kg, com_m = mass.robot_mass_com(load_config(overrides={key: value}))
    if moves == "mass":
        assert abs(mass_kg - base_mass) > 1e-6
    else:
        assert np.max(np.abs(com_m - base_com)) > 1e-6
    again_mass, again_com = mass.robot_mass_com(load_config())
    assert again_mass == base_mass and np.array_equal(again_com, base_com)
