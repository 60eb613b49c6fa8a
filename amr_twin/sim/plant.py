"""The plant between the Arduino's pins and the wheels: battery, drivers, hub motors.

Per wheel, a ZS-X11D1-like driver reads its pins (:class:`~amr_twin.base.pins.DriverPins`)
and powers a BLDC hub motor from the battery:

- STOP low (disabled) or the e-stop relays open: phases open, zero current, the
  wheel coasts.
- BRAKE high: phases shorted through the low-side switches: zero phase voltage, so
  the motor brakes with ``-Kt Ke / R * omega``, its current ``Ke omega / R`` bounded by
  the switches' rating (``driver.brake_current_limit_a``); no torque at standstill
  beyond the motor's own friction.
- otherwise: phase voltage ``v = dir * V_batt * clip(gain * (duty - deadband) / (1 - deadband), 0, 1)``.
  The driver treats the PWM input as a speed demand, hence a gain (calibrated), one per board
  (``driver_left.gain``, ``driver_right.gain``: the robot has two ZS-X11D1 boards).

The motor is the quasi-static DC model of MuJoCo's documentation, evaluated in C
by an affine actuator: ``torque = Kt/R * v - Kt*Ke/R * omega``, clipped at
``Kt * I_max`` (current limit). The battery (:mod:`amr_twin.sim.battery`: open-circuit
voltage from state of charge, internal resistance) is updated on the loop's record grid (every 10 ms,
whatever the events in between, so that a run does not depend on how the loop
splits it), from the currents drawn at that instant: each
driver's input current (``v_phase * i_phase / V_batt``, a lossless power stage, plus
its quiescent current) and the auxiliary load (mini PC, electronics) at constant power.

Currents, as the CSV and recordings name them: ``current_a_left``/``right`` is each
motor's (DC-equivalent phase) current, the one that makes torque (``Kt * I``);
``battery_a`` the pack's current; ``supply_a`` one driver's input current.
"""

from __future__ import annotations

import numpy as np

from amr_twin.model.config import TwinConfig
from amr_twin.model.config_sections import DriverBoardCfg, DriverCfg, MotorCfg
from amr_twin.sim.battery import BRAKE, COAST, DRIVE, Battery
from amr_twin.sim.physics import Physics
from amr_twin.base.pins import DriverPins


MODE_CODES = {"drive": DRIVE, "coast": COAST, "brake": BRAKE}
"""Motor modes as recorded (:attr:`amr_twin.recording.recorder.RunSeries.mode`)."""


def motor_currents_a(cfg: TwinConfig, voltage_v: np.ndarray, speed_rad_s: np.ndarray,
                     mode: np.ndarray) -> np.ndarray:
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
        limit = np.where(mode[:, w] == MODE_CODES["brake"], cfg.driver.brake_current_limit_a, m.current_limit_a)
        out[:, w] = np.where(mode[:, w] == MODE_CODES["coast"], 0.0, np.clip(i, -limit, limit))
    return out


class Plant:
    """Drivers, motors and battery of both wheels, applied to a :class:`Physics`."""

    def __init__(self, cfg: TwinConfig, physics: Physics):
        self.cfg, self.physics = cfg, physics
        self.driver: DriverCfg = cfg.driver
        self.boards: tuple[DriverBoardCfg, DriverBoardCfg] = (cfg.driver_left, cfg.driver_right)
        self.motors: tuple[MotorCfg, MotorCfg] = (cfg.motor_left, cfg.motor_right)
        self.battery = Battery(cfg.battery)
        self.estop = False
        self.supply_cut = False  # fault injection (amr_twin/sim/fault_injector.py): drivers unpowered, coast
        self.voltage_v = [0.0, 0.0]
        self.mode = ["coast", "coast"]
        # per wheel, plain floats: Ke, R, current limit
        self._motor_consts = [(m.ke_v_s_rad, m.resistance_ohm, m.current_limit_a) for m in self.motors]
        self._quiescent2_a = 2 * self.driver.quiescent_current_a
        self._aux_w = cfg.battery.auxiliary_power_w
        self.battery.connect(physics, physics.wheel_dof, self._motor_consts, self.driver.brake_current_limit_a,
                             self._quiescent2_a, self._aux_w)

    def phase_voltage_v(self, pins: DriverPins, wheel: int) -> float:
        """Signed phase voltage, V, that wheel ``wheel``'s driver (0 left, 1 right) applies for these pins."""
        db = self.driver.deadband_duty
        level = min(1.0, max(0.0, self.boards[wheel].gain * (pins.duty - db) / (1.0 - db)))
        return pins.direction * level * self.battery.terminal_v()

    def apply(self, pins: tuple[DriverPins, DriverPins]) -> None:
        """Set both motors from the pins (phase voltage from the battery's present terminal voltage)."""
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
            self.physics.set_motor(w, mode, volt, limit)

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
        for mode, volt, speed, (ke, r_ohm, limit) in zip(self.mode, self.voltage_v, speeds, self._motor_consts):
            if mode == "coast":
                out.append(0.0)
                continue
            if mode == "brake":
                limit = brake_limit_a
            i = (volt - ke * speed) / r_ohm
            out.append(max(-limit, min(limit, i)))
        return out
