"""Mass properties of the robot's links from its parametric geometry (closed forms).

The AISI304 frame is built of square tubes (four corner posts and, on each of the
three floors, a perimeter of four rails plus one cross rail over the axle); each
tube is an outer box minus its bore. Floors (a) and (c) carry a steel sheet, floor
(b) the aluminium deck. Components are solid boxes of their estimated mass. The
hub motors' stators (the non-rotating share of their mass) ride on the chassis.
Everything is summed into the chassis link's mass, centre of mass and inertia
(parallel-axis theorem), but the sensors that have a link of their own (the
LiDAR on ``laser``, the IMU board on ``imu_link``, the UWB tag on ``uwb_tag``:
:func:`sensor_link_inertials`); the xacro draws the same members from
:func:`frame_members`.

Every part is a solid of uniform density with a textbook inertia (:mod:`.inertia`): a box
``m (b^2 + c^2) / 12``..., a cylinder ``m r^2 / 2`` about its axis and ``m (3 r^2 + h^2) / 12``
across, a sphere ``2 m r^2 / 5`` (tests/model/test_mass.py checks them against trimesh's
meshes). No mesh library on the model build's path: this module costs microseconds.
"""

from __future__ import annotations

import numpy as np

from amr_twin.model.config import TwinConfig
from amr_twin.model.inertia import Inertial, box_inertia, combine, cylinder_inertia, sphere_inertia


def _box(extents, center, mass_kg: float | None = None, density: float | None = None) -> Inertial:
    """A solid box of ``extents`` at ``center``, of a given mass or density (kg/m^3)."""
    if mass_kg is None:
        mass_kg = density * float(np.prod(extents))
    return Inertial(float(mass_kg), np.asarray(center, float), box_inertia(extents, mass_kg))


def _tube(extents, center, axis: int, wall_m: float, density: float) -> Inertial:
    """A square tube along ``axis``: outer box minus the bore."""
    outer = _box(extents, center, density=density)
    bore_extents = [e - 2 * wall_m if k != axis else e for k, e in enumerate(extents)]
    bore = _box(bore_extents, center, density=density)
    return Inertial(
        outer.mass_kg - bore.mass_kg, outer.com_m, outer.inertia_kg_m2 - bore.inertia_kg_m2
    )


def frame_members(
    cfg: TwinConfig,
) -> list[tuple[str, tuple[float, float, float], tuple[float, float, float], int]]:
    """The frame's tubes as ``(name, center_m, extents_m, axis)`` in base_link.

    Rails sit under their floor (top face at the floor height); posts join the
    corners from the bottom of floor (a)'s rails to the top of floor (c)'s.
    """
    c = cfg.chassis
    t, L, W = c.tube_outer_m, c.length_m, c.width_m
    members = []
    for tag, z_top in (("a", c.floor_a_z_m), ("b", c.floor_b_z_m), ("c", c.floor_c_z_m)):
        z = z_top - t / 2
        for side, y in (("left", W / 2 - t / 2), ("right", -(W / 2 - t / 2))):
            members.append((f"rail_{tag}_{side}", (0.0, y, z), (L, t, t), 0))
        for end, x in (("front", L / 2 - t / 2), ("rear", -(L / 2 - t / 2)), ("mid", 0.0)):
            members.append((f"rail_{tag}_{end}", (x, 0.0, z), (t, W - 2 * t, t), 1))
    z0, z1 = c.floor_a_z_m - t, c.floor_c_z_m
    for name, x, y in (("fl", 1, 1), ("fr", 1, -1), ("rl", -1, 1), ("rr", -1, -1)):
        members.append(
            (
                f"post_{name}",
                (x * (L / 2 - t / 2), y * (W / 2 - t / 2), (z0 + z1) / 2),
                (t, t, z1 - z0),
                2,
            )
        )
    return members


def frame_inertial(cfg: TwinConfig) -> Inertial:
    """The bare AISI304 tube frame."""
    c = cfg.chassis
    return combine(
        [
            _tube(ext, ctr, axis, c.tube_wall_m, c.steel_density_kg_m3)
            for _, ctr, ext, axis in frame_members(cfg)
        ]
    )


def plates(
    cfg: TwinConfig,
) -> list[tuple[str, tuple[float, float, float], tuple[float, float, float], float]]:
    """Floor plates as ``(name, center_m, extents_m, density_kg_m3)``."""
    c, d = cfg.chassis, cfg.deck
    L, W, s = c.length_m, c.width_m, c.sheet_thickness_m
    return [
        ("floor_a", (0.0, 0.0, c.floor_a_z_m + s / 2), (L, W, s), c.steel_density_kg_m3),
        (
            "floor_b",
            (0.0, 0.0, c.floor_b_z_m + d.thickness_m / 2),
            (L, W, d.thickness_m),
            d.density_kg_m3,
        ),
        ("floor_c", (0.0, 0.0, c.floor_c_z_m + s / 2), (L, W, s), c.steel_density_kg_m3),
    ]


SENSOR_LINKS = {"laser": "lidar", "imu_link": "imu"}
"""URDF link -> the component whose mass it carries (the UWB tag is not a component)."""
LIDAR_BASE_BELOW_OPTICS_M = 0.04
"""RPLIDAR A1: the ``laser`` frame (optical centre) is about 4 cm above the unit's base (datasheet
drawing)."""


def sensor_link_inertials(cfg: TwinConfig) -> dict[str, Inertial]:
    """Mass properties of the sensor links, each in its own link frame (solid boxes).

    ``laser``: the A1 (its box's base 4 cm below the optical centre), ``imu_link``: the
    IMU breakout centred on its frame, ``uwb_tag``: the tag board centred on its frame.
    """
    lidar, imu, uwb = cfg.components.lidar, cfg.components.imu, cfg.uwb
    return {
        "laser": _box(
            lidar.size_m,
            (0.0, 0.0, lidar.size_m[2] / 2 - LIDAR_BASE_BELOW_OPTICS_M),
            mass_kg=lidar.mass_kg,
        ),
        "imu_link": _box(imu.size_m, (0.0, 0.0, 0.0), mass_kg=imu.mass_kg),
        "uwb_tag": _box(uwb.tag_size_m, (0.0, 0.0, 0.0), mass_kg=uwb.tag_mass_kg),
    }


def sensor_inertials_in_base(cfg: TwinConfig) -> list[Inertial]:
    """:func:`sensor_link_inertials` moved into ``base_link`` (the links' fixed joints: LiDAR,
    IMU and UWB tag positions)."""
    at = {
        "laser": cfg.components.lidar.pos_m,
        "imu_link": cfg.components.imu.pos_m,
        "uwb_tag": cfg.uwb.tag_pos_m,
    }
    return [
        Inertial(i.mass_kg, i.com_m + np.asarray(at[name], float), i.inertia_kg_m2)
        for name, i in sensor_link_inertials(cfg).items()
    ]


def chassis_inertial(cfg: TwinConfig) -> Inertial:
    """Chassis link: frame, plates, the components without a link of their own and the two
    stators."""
    parts = [frame_inertial(cfg)]
    parts += [_box(ext, ctr, density=rho) for _, ctr, ext, rho in plates(cfg)]
    on_links = set(SENSOR_LINKS.values())
    parts += [
        _box(comp.size_m, comp.pos_m, mass_kg=comp.mass_kg)
        for name, comp in cfg.components.items()
        if comp.mass_kg > 0 and name not in on_links
    ]
    w = cfg.wheel
    stator_kg = w.mass_kg * (1 - w.rotor_fraction)
    for sign in (1, -1):
        parts.append(
            _box(
                (0.8 * w.radius_m,) * 3,
                (0.0, sign * w.separation_m / 2, w.radius_m),
                mass_kg=stator_kg,
            )
        )
    return combine(parts)


def wheel_inertial(cfg: TwinConfig) -> Inertial:
    """Rotating share of a hub motor (rotor, magnets, tyre) as a solid cylinder, axis along y."""
    w = cfg.wheel
    mass = w.mass_kg * w.rotor_fraction
    i = cylinder_inertia(w.radius_m, w.width_m, mass)  # axis along z
    perm = [0, 2, 1]  # cylinder z -> link y
    return Inertial(mass, np.zeros(3), i[np.ix_(perm, perm)])


def caster_inertial(cfg: TwinConfig) -> Inertial:
    """Caster ball unit (housing, spring, ball) as a solid sphere."""
    k = cfg.caster
    return Inertial(k.mass_kg, np.zeros(3), sphere_inertia(k.ball_diameter_m / 2, k.mass_kg))


def robot_mass_kg(cfg: TwinConfig) -> float:
    """Total mass without payload."""
    return (
        chassis_inertial(cfg).mass_kg
        + 2 * wheel_inertial(cfg).mass_kg
        + 4 * caster_inertial(cfg).mass_kg
        + sum(i.mass_kg for i in sensor_link_inertials(cfg).values())
    )


_unloaded_memo: dict[tuple, tuple] = {}


def _robot_key(cfg: TwinConfig) -> tuple:
    """The sections the unloaded robot's mass properties are built from (hashable: frozen
    models)."""
    return cfg.chassis, cfg.deck, cfg.components, cfg.wheel, cfg.caster, cfg.uwb


def _unloaded_parts(cfg: TwinConfig) -> tuple:
    """The robot's parts without the payload (base_link), kept per robot: a sweep's points
    differ by their payload only, and each solves the statics several times (~2 ms a build)."""
    key = _robot_key(cfg)
    parts = _unloaded_memo.get(key)
    if parts is not None:
        return parts
    w, k = cfg.wheel, cfg.caster
    parts = [chassis_inertial(cfg), *sensor_inertials_in_base(cfg)]
    rotor = wheel_inertial(cfg)
    parts += [
        Inertial(
            rotor.mass_kg, np.array([0.0, s * w.separation_m / 2, w.radius_m]), rotor.inertia_kg_m2
        )
        for s in (1, -1)
    ]
    ball = caster_inertial(cfg)
    r_ball = k.ball_diameter_m / 2
    parts += [
        Inertial(
            ball.mass_kg, np.array([sx * k.x_m, sy * k.y_m, r_ball - k.drop_m]), ball.inertia_kg_m2
        )
        for sx, sy in ((1, 1), (1, -1), (-1, 1), (-1, -1))
    ]
    for part in parts:
        part.com_m.setflags(write=False)
        part.inertia_kg_m2.setflags(write=False)
    if len(_unloaded_memo) > 64:
        _unloaded_memo.clear()
    _unloaded_memo[key] = parts = tuple(parts)
    return parts


_loaded_memo: dict[tuple, tuple] = {}


def robot_mass_com(cfg: TwinConfig) -> tuple[float, np.ndarray]:
    """Total mass (kg) and centre of mass ((3,), m, base_link, read-only) with the payload;
    kept per robot and payload (a sweep point solves the statics five times)."""
    c, p = cfg.chassis, cfg.payload
    key = (*_robot_key(cfg), p)
    kept = _loaded_memo.get(key)
    if kept is not None:
        return kept
    parts = list(_unloaded_parts(cfg))
    if p.mass_kg > 0:
        z = c.floor_c_z_m + c.sheet_thickness_m + p.size_m[2] / 2
        parts.append(Inertial(p.mass_kg, np.array([p.xy_m[0], p.xy_m[1], z]), np.zeros((3, 3))))
    total = combine(parts)
    total.com_m.setflags(write=False)
    if len(_loaded_memo) > 64:
        _loaded_memo.clear()
    _loaded_memo[key] = kept = (total.mass_kg, total.com_m)
    return kept
