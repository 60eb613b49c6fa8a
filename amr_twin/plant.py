"""The plant between the Arduino's pins and the wheels: battery, drivers, hub motors.

Per wheel, a ZS-X11D1-like driver reads its pins (:class:`~amr_twin.pins.DriverPins`)
and powers a BLDC hub motor from the battery:

- STOP low (disabled) or the e-stop relays open: phases open, zero current, the
  wheel coasts.
- BRAKE high: phases shorted and held, the wheel cannot turn (strong damping).
- otherwise: phase voltage ``v = dir * V_batt * clip(gain * (duty - deadband) / (1 - deadband), 0, 1)``.
  The driver treats the PWM input as a speed demand, hence a gain (calibrated).

The motor is the quasi-static DC model of MuJoCo's documentation, evaluated in C
by an affine actuator: ``torque = Kt/R * v - Kt*Ke/R * omega``, clipped at
``Kt * I_max`` (current limit). The battery (open-circuit voltage from state of
charge, internal resistance) is updated at every event of the loop, i.e. each time
the pins may change, from the currents drawn since the previous update.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from .config import TwinConfig
from .config_sections import BatteryCfg, DriverCfg, MotorCfg
from .physics import Physics
from .pins import DriverPins


@dataclass
class Battery:
    """Lithium pack: OCV piecewise linear in SOC through (0, empty), (0.5, nominal), (1, full)."""

    cfg: BatteryCfg
    soc: float = field(init=False)
    current_a: float = 0.0

    def __post_init__(self) -> None:
        self.soc = self.cfg.soc_initial

    def ocv_v(self) -> float:
        """Open-circuit voltage at the present state of charge, V."""
        c, s = self.cfg, min(1.0, max(0.0, self.soc))
        if s < 0.5:
            return c.v_empty_v + (c.v_nominal_v - c.v_empty_v) * s / 0.5
        return c.v_nominal_v + (c.v_full_v - c.v_nominal_v) * (s - 0.5) / 0.5

    def terminal_v(self) -> float:
        """Terminal voltage under the present current, V."""
        return self.ocv_v() - self.cfg.internal_resistance_ohm * self.current_a

    def draw(self, current_a: float, duration_s: float) -> None:
        """Drain ``current_a`` (negative: charge, regenerative braking) for ``duration_s``."""
        self.current_a = current_a
        self.soc -= current_a * duration_s / (self.cfg.capacity_ah * 3600.0)


class Plant:
    """Drivers, motors and battery of both wheels, applied to a :class:`Physics`."""

    def __init__(self, cfg: TwinConfig, physics: Physics):
        self.physics = physics
        self.driver: DriverCfg = cfg.driver
        self.motors: tuple[MotorCfg, MotorCfg] = (cfg.motor_left, cfg.motor_right)
        self.battery = Battery(cfg.battery)
        self.estop = False
        self.voltage_v = [0.0, 0.0]
        self.mode = ["coast", "coast"]
        self._t_last_s = physics.time_s

    def phase_voltage_v(self, pins: DriverPins) -> float:
        """Signed phase voltage the driver applies for these pins while enabled."""
        db = self.driver.deadband_duty
        level = min(1.0, max(0.0, self.driver.gain * (pins.duty - db) / (1.0 - db)))
        return pins.direction * level * self.battery.terminal_v()

    def apply(self, pins: tuple[DriverPins, DriverPins]) -> None:
        """Account the battery since the last call, then set both motors from the pins."""
        self._account_battery()
        for w, p in enumerate(pins):
            if self.estop or not p.enabled:
                mode, volt = "coast", 0.0
            elif p.braking:
                mode, volt = "brake", 0.0
            else:
                mode, volt = "drive", self.phase_voltage_v(p)
            self.mode[w], self.voltage_v[w] = mode, volt
            self.physics.set_motor(w, mode, volt, self.driver.brake_damping_nm_s_rad)

    def set_estop(self, pressed: bool, pins: tuple[DriverPins, DriverPins]) -> None:
        """The mushroom button: relays cut both motors' phases while pressed."""
        self.estop = pressed
        self.apply(pins)

    def motor_currents_a(self) -> list[float]:
        """Phase current of each motor now, A (0 when coasting or braking)."""
        out = []
        for w, m in enumerate(self.motors):
            if self.mode[w] != "drive":
                out.append(0.0)
                continue
            out.append(self.physics.motor_current_a(w, self.voltage_v[w], m.ke_v_s_rad, m.resistance_ohm,
                                                    m.current_limit_a))
        return out

    def _account_battery(self) -> None:
        t = self.physics.time_s
        dt = t - self._t_last_s
        self._t_last_s = t
        v_batt = max(1.0, self.battery.terminal_v())
        # power balance through the drivers: I_batt = sum(v_phase * i_phase) / V_batt
        i_batt = sum(v * i for v, i in zip(self.voltage_v, self.motor_currents_a())) / v_batt
        self.battery.draw(i_batt, dt)
