"""Checks of a start pose, before a run: the robot clear of the world, and held up.

:func:`check_start` refuses a start pose where the robot overlaps the world (the contacts
classified as :mod:`amr_twin.sim.collisions` classifies them during a run), and
:func:`check_supported` one where nothing holds it up after settling: no wheel or caster
touches anything and no fixture holds the base (a world without a floor; the ``stand``
world's weld, the work station of fig. 5.1, holds it with the wheels in the air).

Part of the physics layer (``PHYSICS_LAYER``): places the robot at its start pose in MjData and
checks its contacts (``mj_forward``).
"""

from __future__ import annotations

import mujoco

from amr_twin.sim.geom_roles import GeomRoles, collision_contacts

PHYSICS_LAYER = True


class StartPoseError(ValueError):
    """The robot cannot start where asked (inside an obstacle, nothing under it); one line."""


def check_start(physics, where: str) -> None:
    """Raise :class:`StartPoseError` if the robot overlaps the world where it was placed.

    ``physics`` has just been built (``mj_forward`` ran: the contacts are those of
    the start pose); ``where`` names the pose for the message.
    """
    roles = GeomRoles(physics)
    mujoco.mj_forward(physics.model, physics.data)
    hits, _ = collision_contacts(roles, physics.data)
    if hits:
        names = sorted({roles.world_name(w) for _i, _r, w in hits})
        shown = ", ".join(names[:5]) + (f" and {len(names) - 5} more" if len(names) > 5 else "")
        raise StartPoseError(
            f"{where}: the robot overlaps {shown} there; "
            "choose a free start pose (--start X_M,Y_M,YAW_DEG)"
        )


def held_by_fixture(physics) -> bool:
    """Whether an active weld holds the robot's base where it stands (the ``stand`` world's
    fixture, the work station of fig. 5.1: chassis held, wheels free)."""
    m, d = physics.model, physics.data
    weld = mujoco.mjtEq.mjEQ_WELD
    return any(
        m.eq_type[i] == weld
        and d.eq_active[i]
        and physics.base_body in (m.eq_obj1id[i], m.eq_obj2id[i])
        for i in range(m.neq)
    )


def check_supported(physics, where: str) -> None:
    """Raise :class:`StartPoseError` if, after settling, no wheel or caster touches anything
    and no fixture holds the base (:func:`held_by_fixture`)."""
    if held_by_fixture(physics):
        return
    d = physics.data
    support = set(physics.support.geoms.values())
    touching = (
        any(g1 in support or g2 in support for g1, g2 in d.contact.geom.tolist())
        if d.ncon
        else False
    )
    if not touching:
        z = float(physics.data.qpos[physics.root_qpos + 2])
        raise StartPoseError(
            f"{where}: nothing holds the robot up (no wheel or caster touches the ground "
            f"after settling, base at z = {z:.2f} m): the world has no floor there"
        )
