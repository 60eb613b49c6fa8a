"""The robot's two wheel motors in MuJoCo: the three motor modes (drive, coast, brake) set on the
actuators' parameters between steps (the per-step torque stays in C). A braked motor is a motor at
zero phase voltage (phases shorted): torque ``-Kt Ke / R * omega``, within the brake's own current
limit.

Part of the physics layer (``PHYSICS_LAYER``): writes the actuators' controls in MjData and their
parameters in the model."""

from __future__ import annotations

import mujoco
import numpy as np

PHYSICS_LAYER = True


class Motors:
    """The motors of the actuators ``actuator`` (left, right) of ``model`` and ``data``; the
    torque range, gain and back-EMF bias as built are the drive's."""

    def __init__(self, model: mujoco.MjModel, data: mujoco.MjData, actuator: np.ndarray):
        self.model, self.data, self.actuator = model, data, actuator
        self._drive_range = model.actuator_forcerange[actuator].copy()
        self._drive_gain = model.actuator_gainprm[actuator, 0].copy()
        self._drive_bias = model.actuator_biasprm[actuator, 2].copy()

    def set(
        self, wheel: int, mode: str, voltage_v: float = 0.0, torque_limit_nm: float | None = None
    ) -> None:
        """Set one motor's mode: ``"drive"`` at a phase voltage (V), ``"coast"`` or ``"brake"``.

        ``torque_limit_nm`` bounds the torque (N m: the driver's current limit times Kt; for
        ``"brake"``, the shorted phases' own limit); default: the drive limit.
        """
        m, a = self.model, self.actuator[wheel]
        limit = (
            self._drive_range[wheel]
            if torque_limit_nm is None
            else (-torque_limit_nm, torque_limit_nm)
        )
        m.actuator_forcerange[a] = limit
        if mode in ("drive", "brake"):  # brake: phases shorted, i.e. zero phase voltage
            m.actuator_gainprm[a, 0] = self._drive_gain[wheel]
            m.actuator_biasprm[a, 2] = self._drive_bias[wheel]
            self.data.ctrl[a] = voltage_v if mode == "drive" else 0.0
        elif mode == "coast":  # phases open: no current, no torque
            m.actuator_gainprm[a, 0] = 0.0
            m.actuator_biasprm[a, 2] = 0.0
            self.data.ctrl[a] = 0.0
        else:
            raise ValueError(f"mode must be drive, coast or brake, got {mode!r}")
