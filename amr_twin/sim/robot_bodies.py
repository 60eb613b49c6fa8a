"""Which bodies and geoms of a world belong to which robot, and a robot's geoms hidden from its
own rays.

A robot is a kinematic tree whose root body, ``<prefix>base_link``, hangs on a free joint from
the world (:func:`amr_twin.model.build.build` attaches one per robot). In a world of several
robots each robot's LiDAR and UWB rays must see the others' bodies but never its own:
:class:`OwnGeoms` moves the robot's visual geoms (group 1, the true shape; the collision geoms
are invisible to rays) out of every seen group while it casts.

Part of the physics layer (``PHYSICS_LAYER``): reads MjModel's body tree and writes its
``geom_group`` around a robot's ray casts.
"""

from __future__ import annotations

import mujoco
import numpy as np

from amr_twin.model.robot_spec import GROUP_VISUAL

PHYSICS_LAYER = True

ROOT_BODY = "base_link"
HIDDEN_GROUP = 3
"""The group a robot's own visual geoms stand in while it casts: no ray mask holds it."""
_QPOS_WIDTH = {int(mujoco.mjtJoint.mjJNT_FREE): 7, int(mujoco.mjtJoint.mjJNT_BALL): 4}
_DOF_WIDTH = {int(mujoco.mjtJoint.mjJNT_FREE): 6, int(mujoco.mjtJoint.mjJNT_BALL): 3}


def robot_roots(model: mujoco.MjModel) -> np.ndarray:
    """(nbody,) bool: which bodies are a robot's root (``<prefix>base_link`` on a free joint)."""
    out = np.zeros(model.nbody, bool)
    for b in range(1, model.nbody):
        name = mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_BODY, b) or ""
        out[b] = (
            model.body_rootid[b] == b
            and name.endswith(ROOT_BODY)
            and model.body_jntnum[b] > 0
            and model.jnt_type[model.body_jntadr[b]] == mujoco.mjtJoint.mjJNT_FREE
        )
    return out


def robot_indices(model: mujoco.MjModel, body: int) -> tuple[np.ndarray, np.ndarray]:
    """``(qpos, dof)``: the indices of ``qpos`` and of the dof arrays (``qvel``, ...) that belong to
    the joints of the robot (the kinematic tree) ``body`` is part of, in order."""
    joints = np.flatnonzero(model.body_rootid[model.jnt_bodyid] == model.body_rootid[int(body)])
    qpos = [
        np.arange(a, a + _QPOS_WIDTH.get(int(t), 1))
        for a, t in zip(model.jnt_qposadr[joints], model.jnt_type[joints])
    ]
    dof = [
        np.arange(a, a + _DOF_WIDTH.get(int(t), 1))
        for a, t in zip(model.jnt_dofadr[joints], model.jnt_type[joints])
    ]
    return np.concatenate(qpos), np.concatenate(dof)


def robot_name(model: mujoco.MjModel, root: int) -> str:
    """The name of the robot whose root body is ``root``: its prefix without the slash
    (``amr-2``)."""
    name = mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_BODY, int(root)) or ""
    return name.removesuffix(ROOT_BODY).rstrip("/")


class OwnGeoms:
    """The visual geoms of the robot that ``body`` belongs to, hidden from ray masks inside a
    ``with`` block (module notes). :attr:`others`: whether the world has other robots to see; a
    lone robot's block changes nothing."""

    def __init__(self, model: mujoco.MjModel, body: int):
        roots = model.body_rootid[model.geom_bodyid]
        own = model.body_rootid[int(body)]
        robots = robot_roots(model)[roots]
        self.others = bool((robots & (roots != own)).any())
        """Whether another robot's geoms are in the world."""
        self._model = model
        self._ids = np.flatnonzero((roots == own) & (model.geom_group == GROUP_VISUAL))

    def __enter__(self) -> "OwnGeoms":
        if self.others:
            self._model.geom_group[self._ids] = HIDDEN_GROUP
        return self

    def __exit__(self, *exc) -> None:
        if self.others:
            self._model.geom_group[self._ids] = GROUP_VISUAL

    def seeing_others(self, groups: np.ndarray) -> np.ndarray:
        """A copy of the ray mask ``groups`` (6,) uint8 that also sees the other robots' visual
        geoms when there are any."""
        out = np.array(groups, np.uint8)
        if self.others:
            out[GROUP_VISUAL] = 1
        return out
