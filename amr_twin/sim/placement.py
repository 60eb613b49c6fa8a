"""Teleporting one robot in its world (``Twin.reset_world``, ``Twin.set_robot_pose``): its joints
put to a settled rest state at another pose, every velocity zero, and put back.

Part of the physics layer (``PHYSICS_LAYER``): writes ``qpos``, ``qvel`` of MjData and runs
``mj_forward``."""

from __future__ import annotations

import math

import mujoco
import numpy as np

from amr_twin.analysis.se2 import yaw_of_quaternion

PHYSICS_LAYER = True


class Placement:
    """The robot of ``model`` and ``data`` whose free joint's positions begin at ``root_qpos``,
    wheels' at ``wheel_qpos``; ``own_qpos``, ``own_dof``: its joints' indices (the others stay)."""

    def __init__(self, model, data, root_qpos, wheel_qpos, own_qpos, own_dof):
        self.model, self.data = model, data
        self.root_qpos, self.wheel_qpos = root_qpos, wheel_qpos
        self._own_qpos, self._own_dof = own_qpos, own_dof

    def positions(self) -> np.ndarray:
        """A copy of every joint position (``qpos``): a rest state for :meth:`place`."""
        return self.data.qpos.copy()

    def place(self, x_m: float, y_m: float, yaw_rad: float, rest: np.ndarray) -> np.ndarray:
        """Teleport the robot to ``x_m, y_m`` heading ``yaw_rad`` (world frame), standing as in
        ``rest`` (:meth:`positions` of it settled: its height, tilt, tyre and caster springs), every
        velocity zero; the wheels keep their angles (their hall sensors see no jump). Returns the
        positions before, to put back with :meth:`restore`."""
        d, a = self.data, self.root_qpos
        before = d.qpos.copy()
        wheels = d.qpos[self.wheel_qpos].copy()
        d.qpos[self._own_qpos] = rest[self._own_qpos]  # this robot's joints; the others stay
        d.qpos[self.wheel_qpos] = wheels
        turn = 0.5 * (yaw_rad - yaw_of_quaternion(*rest[a + 3 : a + 7]))
        quat = np.empty(4)
        mujoco.mju_mulQuat(
            quat, np.array([math.cos(turn), 0.0, 0.0, math.sin(turn)]), rest[a + 3 : a + 7]
        )
        d.qpos[a : a + 3] = (x_m, y_m, rest[a + 2])
        d.qpos[a + 3 : a + 7] = quat
        self._at_rest()
        return before

    def restore(self, qpos: np.ndarray) -> None:
        """Put back the positions :meth:`place` returned, the robot's velocities zero."""
        self.data.qpos[:] = qpos
        self._at_rest()

    def _at_rest(self) -> None:
        d = self.data
        d.qvel[self._own_dof] = 0.0
        d.qacc_warmstart[self._own_dof] = 0.0
        mujoco.mj_forward(self.model, d)
