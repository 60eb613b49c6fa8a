"""The MuJoCo bodies of the actors: a person (legs, torso, head; :func:`add_person`) and a pallet
jack (forks, body, handle; :func:`add_pallet_jack`), their geoms added to a mocap body with the
contact priority and compliance that let a touch take the actor's (:data:`PRIORITY`)."""

from __future__ import annotations

_RGBA = {
    "legs": [0.15, 0.20, 0.35, 1.0],
    "torso": [1.0, 0.55, 0.05, 1.0],
    "head": [0.85, 0.70, 0.55, 1.0],
    "jack": [0.80, 0.10, 0.10, 1.0],
    "handle": [0.15, 0.15, 0.15, 1.0],
}


PRIORITY = 2
"""The actors' colliding geoms' contact priority: above the robot's wheels and casters (1), so that
a touch takes the actor's compliance (``actors.<kind>.contact_timeconst_s``)."""


def _touching(k) -> dict:
    """What an actor's colliding geom touches the robot with: its priority and compliance."""
    return {"priority": PRIORITY, "solref": [k.contact_timeconst_s, 1.0]}


def add_person(body, name: str, p) -> None:
    """A person's geoms on ``body`` (an ``MjsBody``), named ``<name>/<part>``; ``p``: its params."""
    import mujoco

    cyl, box, sphere = (
        mujoco.mjtGeom.mjGEOM_CYLINDER,
        mujoco.mjtGeom.mjGEOM_BOX,
        mujoco.mjtGeom.mjGEOM_SPHERE,
    )
    half_leg = p.leg_length_m / 2
    for side, y in (("left", p.leg_spacing_m / 2), ("right", -p.leg_spacing_m / 2)):
        body.add_geom(
            name=f"{name}/leg_{side}",
            type=cyl,
            size=[p.leg_radius_m, half_leg, 0],
            pos=[0, y, half_leg],
            rgba=_RGBA["legs"],
            **_touching(p),
        )
    head_r = 0.1 * p.height_m / 1.7
    torso_h = p.height_m - 2 * head_r - p.leg_length_m
    body.add_geom(
        name=f"{name}/torso",
        type=box,
        size=[p.torso_depth_m / 2, p.torso_width_m / 2, torso_h / 2],
        pos=[0, 0, p.leg_length_m + torso_h / 2],
        rgba=_RGBA["torso"],
        contype=0,
        conaffinity=0,
    )
    body.add_geom(
        name=f"{name}/head",
        type=sphere,
        size=[head_r, 0, 0],
        pos=[0, 0, p.height_m - head_r],
        rgba=_RGBA["head"],
        contype=0,
        conaffinity=0,
    )


def add_pallet_jack(body, name: str, j) -> None:
    """A pallet jack's geoms on ``body``, named ``<name>/<part>``; ``j``: ``actors.pallet_jack``."""
    import mujoco

    box, cyl = mujoco.mjtGeom.mjGEOM_BOX, mujoco.mjtGeom.mjGEOM_CYLINDER
    front, back = j.length_m / 2, -j.length_m / 2
    heel = front - j.fork_length_m  # the forks' back end: the steer frame behind it
    for side, y in (
        ("left", (j.width_m - j.fork_width_m) / 2),
        ("right", -(j.width_m - j.fork_width_m) / 2),
    ):
        body.add_geom(
            name=f"{name}/fork_{side}",
            type=box,
            size=[j.fork_length_m / 2, j.fork_width_m / 2, j.fork_height_m / 2],
            pos=[(front + heel) / 2, y, j.fork_height_m / 2],
            rgba=_RGBA["jack"],
            **_touching(j),
        )
    body.add_geom(
        name=f"{name}/frame",
        type=box,
        size=[(heel - back) / 2, j.width_m / 2, j.frame_height_m / 2],
        pos=[(heel + back) / 2, 0, j.frame_height_m / 2],
        rgba=_RGBA["jack"],
        **_touching(j),
    )
    x_pump = back + j.pump_radius_m
    body.add_geom(
        name=f"{name}/pump",
        type=cyl,
        size=[j.pump_radius_m, j.pump_height_m / 2, 0],
        pos=[x_pump, 0, j.pump_height_m / 2],
        rgba=_RGBA["jack"],
        **_touching(j),
    )
    half = (j.handle_height_m - j.pump_height_m) / 2
    body.add_geom(
        name=f"{name}/handle",
        type=cyl,
        size=[0.015, half, 0],
        pos=[x_pump, 0, j.pump_height_m + half],
        rgba=_RGBA["handle"],
        **_touching(j),
    )
    body.add_geom(
        name=f"{name}/grip",
        type=box,
        size=[0.02, 0.18, 0.02],
        pos=[x_pump, 0, j.handle_height_m],
        rgba=_RGBA["handle"],
        contype=0,
        conaffinity=0,
    )
