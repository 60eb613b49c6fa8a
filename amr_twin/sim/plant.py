"""The plant between the Arduino's pins and the wheels: battery, drivers, hub motors.

Reasons and measurements: docs/explanation/architecture.md#amr_twinsimplant."""

from __future__ import annotations

import numpy as np

from amr_twin.model.config import TwinConfig
from amr_twin.model.config_sections import BatteryCfg, DriverBoardCfg, DriverCfg, MotorCfg
from amr_twin.sim.battery import BRAKE, COAST, DRIVE, Battery
from amr_twin.sim.physics import Physics
from amr_twin.base.pins import DriverPins


MODE_CODES = {"drive": DRIVE, "coast": COAST, "brake": BRAKE}
"""Motor modes as recorded (:attr:`amr_twin.recording.recorder.RunSeries.mode`)."""


def motor_currents_a(
    cfg: TwinConfig, voltage_v: np.ndarray, speed_rad_s: np.ndarray, mode: np.ndarray
) -> np.ndarray:
    """Phase currents of both motors from recorded states, A.

    Parameters
    ----------
    voltage_v, speed_rad_s, mode : (n, 2) phase voltage, wheel speed and mode code
        (:data:`MODE_CODES`) of the left and right motor.

    Returns
    -------
    (n, 2) current, + driving forward torque; 0 when coasting, ``-Ke w / R`` braking.
    """
    out = np.zeros(np.shape(speed_rad_s))
    for w, m in enumerate((cfg.motor_left, cfg.motor_right)):
        i = (voltage_v[:, w] - m.ke_v_s_rad * speed_rad_s[:, w]) / m.resistance_ohm
        limit = np.where(
            mode[:, w] == MODE_CODES["brake"], cfg.driver.brake_current_limit_a, m.current_limit_a
        )
        out[:, w] = np.where(
            mode[:, w] == MODE_CODES["coast"], 0.0, np.minimum(np.maximum(i, -limit), limit)
        )
    return out


class Plant:
    """Drivers, motors and battery of both wheels, applied to a :class:`Physics`.

    Args:
        physics: the robot's physics (its wheels' joints and actuators).
        driver: the ZS-X11D1 drivers' common parameters (``driver:``).
        boards: the left and right driver boards (``driver_left:``, ``driver_right:``).
        motors: the left and right hub motors (``motor_left:``, ``motor_right:``).
        battery: the battery (``battery:``).
    """

    def __init__(
        self,
        physics: Physics,
        driver: DriverCfg,
        boards: tuple[DriverBoardCfg, DriverBoardCfg],
        motors: tuple[MotorCfg, MotorCfg],
        battery: BatteryCfg,
    ):
        self.physics = physics
        self.driver = driver
        self.boards = tuple(boards)
        self.motors = tuple(motors)
        self.battery = Battery(battery)
        self.estop = False
        self.supply_cut = (
            False  # fault injection (amr_twin/sim/fault_injector.py): drivers unpowered, coast
        )
        self.voltage_v = [0.0, 0.0]
        self.mode = ["coast", "coast"]
        # per wheel, plain floats: Ke, R, current limit
        self._motor_consts = [
            (m.ke_v_s_rad, m.resistance_ohm, m.current_limit_a) for m in self.motors
        ]
        self._quiescent2_a = 2 * self.driver.quiescent_current_a
        self._aux_w = battery.auxiliary_power_w
        self.battery.connect(
            physics,
            physics.wheel_dof,
            self._motor_consts,
            self.driver.brake_current_limit_a,
            self._quiescent2_a,
            self._aux_w,
        )

    def phase_voltage_v(self, pins: DriverPins, wheel: int) -> float:
        """Signed phase voltage, V, that wheel ``wheel``'s driver (0 left, 1 right) applies for
        these pins."""
        db = self.driver.deadband_duty
        level = min(1.0, max(0.0, self.boards[wheel].gain * (pins.duty - db) / (1.0 - db)))
        return pins.direction * level * self.battery.terminal_v()

    def apply(self, pins: tuple[DriverPins, DriverPins]) -> None:
        """Set both motors from the pins (phase voltage from the battery's present terminal
        voltage)."""
        brake_limit_a = self.driver.brake_current_limit_a
        for w, p in enumerate(pins):
            if self.estop or self.supply_cut or not p.enabled:
                mode, volt = "coast", 0.0
            elif p.braking:
                mode, volt = "brake", 0.0
            else:
                mode, volt = "drive", self.phase_voltage_v(p, w)
            self.mode[w], self.voltage_v[w] = mode, volt
            self.battery.set_motor(w, MODE_CODES[mode], volt)
            limit = self.motors[w].ke_v_s_rad * brake_limit_a if mode == "brake" else None
            self.physics.motors.set(w, mode, volt, limit)

    def set_estop(self, pressed: bool, pins: tuple[DriverPins, DriverPins]) -> None:
        """The mushroom button: relays cut both motors' phases while pressed."""
        self.estop = pressed
        self.apply(pins)

    def motor_currents_a(self) -> list[float]:
        """(2,) phase current of each motor now, A: + driving forward torque; 0 when coasting.

        The scalar form of :func:`motor_currents_a` (plain floats: called every 10 ms)."""
        speeds = self.physics.wheel_speeds_list()
        brake_limit_a = self.driver.brake_current_limit_a
        out = []
        for mode, volt, speed, (ke, r_ohm, limit) in zip(
            self.mode, self.voltage_v, speeds, self._motor_consts
        ):
            if mode == "coast":
                out.append(0.0)
                continue
            if mode == "brake":
                limit = brake_limit_a
            i = (volt - ke * speed) / r_ohm
            out.append(max(-limit, min(limit, i)))
        return out
