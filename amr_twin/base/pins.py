"""The wires between the Arduino and each ZS-X11D1 motor driver.

Levels are those on the pins, as on the hardware (App. B, robot-facts.md):

- ``pwm_counts``: ``analogWrite`` value 0..255 on the PWM pin (duty = counts / 255).
- ``dir_level``: DIR input. The firmware's ``forward()`` writes HIGH and
  ``backward()`` writes LOW (DIR is active low: LOW changes direction). The wiring
  of each hub motor is taken such that HIGH turns that wheel so that the robot
  moves forward (REP-103 +x); the mirror between left and right is in the wiring.
- ``brake_level``: BRAKE input, active high: HIGH = brake applied, wheel held.
- ``stop_level``: STOP input, active low: LOW = drive disabled, the wheel coasts
  (zero phase current). HIGH = enabled.
"""

from __future__ import annotations

from dataclasses import dataclass

HIGH = 1
LOW = 0


@dataclass
class DriverPins:
    """Pin levels of one motor driver, written by the firmware, read by the plant."""

    pwm_counts: int = 0
    dir_level: int = HIGH
    brake_level: int = LOW
    stop_level: int = LOW

    def __post_init__(self) -> None:
        if not 0 <= int(self.pwm_counts) <= 255:
            raise ValueError(f"pwm_counts must be in 0..255, got {self.pwm_counts}")

    @property
    def duty(self) -> float:
        """PWM duty cycle, 0..1."""
        return self.pwm_counts / 255.0

    @property
    def direction(self) -> int:
        """+1 when DIR is HIGH (wheel forward), -1 when LOW (backward)."""
        return 1 if self.dir_level == HIGH else -1

    @property
    def braking(self) -> bool:
        """True when BRAKE is applied (HIGH)."""
        return self.brake_level == HIGH

    @property
    def enabled(self) -> bool:
        """True when STOP is released (HIGH): the driver powers the phases."""
        return self.stop_level == HIGH
