"""A load on the robot's deck at run time (the fleet's pick and drop, ``Twin.set_payload_kg``):
base_link's mass, centre of mass and inertia changed in the MjModel, then ``mj_setConst``.

Part of the physics layer (``PHYSICS_LAYER``): makes a scratch MjData for ``mj_setConst`` and
``mj_fullM``."""

from __future__ import annotations

import mujoco
import numpy as np

PHYSICS_LAYER = True


class Payload:
    """The deck of body ``base_body`` (base_link) of ``model``; its inertial as built is kept."""

    def __init__(self, model: mujoco.MjModel, base_body: int):
        self.model, self.base_body = model, base_body
        b = base_body
        self._base_inertial = tuple(
            a[b].copy()
            for a in (model.body_mass, model.body_ipos, model.body_iquat, model.body_inertia)
        )

    def set_kg(self, mass_kg: float, centre_m, size_m) -> None:
        """Carry a box of ``mass_kg`` (kg; 0: none) and ``size_m`` (3,) centred at ``centre_m`` (3,)
        in base_link, from the next step on: base_link's mass, centre of mass and inertia become
        those of the chassis with the box (parallel-axis theorem), the model's constants
        (subtree masses, inverse weights, the solver's mean inertia) those of the loaded robot at
        qpos0 (``mj_setConst`` on scratch data); 0 puts back base_link as built. In addition to a
        payload body built into the model."""
        m, b, scratch = self.model, self.base_body, mujoco.MjData(self.model)
        m0, c0, q0, i0 = self._base_inertial
        if mass_kg > 0:
            r0 = np.empty(9)
            mujoco.mju_quat2Mat(r0, q0)
            r0 = r0.reshape(3, 3)
            p, a = np.asarray(centre_m, float), np.asarray(size_m, float) ** 2
            total = float(m0) + mass_kg
            com = (m0 * c0 + mass_kg * p) / total
            inertia = r0 @ np.diag(i0) @ r0.T + np.diag(mass_kg / 12 * (a.sum() - a))
            for mass, at in ((m0, c0 - com), (mass_kg, p - com)):
                inertia += mass * (at @ at * np.eye(3) - np.outer(at, at))
            values, vectors, quat = np.empty(3), np.empty(9), np.empty(4)
            mujoco.mju_eig3(values, vectors, quat, inertia.ravel())
            m0, c0, q0, i0 = total, com, quat, values
        m.body_mass[b], m.body_ipos[b], m.body_iquat[b], m.body_inertia[b] = m0, c0, q0, i0
        mujoco.mj_setConst(m, scratch)
        full = np.zeros((m.nv, m.nv))  # MuJoCo's compiler: the mass matrix's mean diagonal at qpos0
        mujoco.mj_fullM(m, scratch, full)
        m.stat.meaninertia = float(np.trace(full)) / m.nv
