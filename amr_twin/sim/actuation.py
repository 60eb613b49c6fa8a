"""The firmware's pins taken by the plant, and the ``on_actuation`` hook: :class:`Actuation`.

The loop hands the pins to the plant (:meth:`Actuation.apply`) whenever the firmware's levels
changed at an instant, and periodically (every divergence check) so that the phase voltages
follow the battery's terminal voltage. A fault (:mod:`amr_twin.sim.fault_injector`) changes
the supply or presses the e-stop through :meth:`Actuation.sag_battery`, :meth:`cut_supply` and
:meth:`press_estop`, which re-apply the pins too. After each application the drive row in force
(:attr:`Actuation.row`: what the recorder pairs with a grid row) is updated and every
``on_actuation`` subscriber is called with the physics time.
"""

from __future__ import annotations

from amr_twin.sim.plant import MODE_CODES


class Actuation:
    """The pins of ``firmware`` applied to ``plant``; ``hooks`` the ``on_actuation`` subscribers (a
    live list)."""

    def __init__(self, plant, firmware, hooks: list):
        self.plant, self.firmware, self._hooks = plant, firmware, hooks
        self.row: list[float] = []
        """The drive in force since the last application: PWM counts L, R (0-255); DIR levels L, R
        (+1 forward, -1 backward); mode codes L, R (:data:`~amr_twin.sim.plant.MODE_CODES`); phase
        voltages L, R, V."""

    def levels(self) -> tuple:
        """The firmware's pin levels now (PWM, DIR, BRAKE, STOP of each driver): equal keys, same
        drive."""
        p0, p1 = self.firmware.pins
        return (
            p0.pwm_counts,
            p0.dir_level,
            p0.brake_level,
            p0.stop_level,
            p1.pwm_counts,
            p1.dir_level,
            p1.brake_level,
            p1.stop_level,
        )

    def apply(self, t_us: int) -> None:
        """Set both motors from the firmware's pins now (physics time ``t_us``) and tell the
        subscribers."""
        pins, plant = self.firmware.pins, self.plant
        plant.apply(pins)
        self._changed(t_us)

    def _changed(self, t_us: int) -> None:
        pins, plant = self.firmware.pins, self.plant
        self.row = [
            pins[0].pwm_counts,
            pins[1].pwm_counts,
            pins[0].direction,
            pins[1].direction,
            MODE_CODES[plant.mode[0]],
            MODE_CODES[plant.mode[1]],
            plant.voltage_v[0],
            plant.voltage_v[1],
        ]
        for fn in self._hooks:
            fn(t_us)

    # -- what a fault changes (amr_twin/sim/fault_injector.py) ---------------------------------
    def sag_battery(self, sag_v: float, t_us: int) -> None:
        """Lower the battery's terminal voltage by ``sag_v`` V (at most to 1 V above nothing), 0 to
        clear."""
        battery = self.plant.battery
        battery.sag_v = (
            min(float(sag_v), battery.ocv_v() - 1.0) if sag_v else 0.0
        )  # the drivers never see < 0 V
        self.apply(t_us)

    def cut_supply(self, cut: bool, t_us: int) -> None:
        """Unpower the drivers (the wheels coast) or power them again."""
        self.plant.supply_cut = cut
        self.apply(t_us)

    def press_estop(self, pressed: bool, t_us: int) -> None:
        """The mushroom button: the relays open both motors' phases while pressed."""
        self.plant.set_estop(pressed, self.firmware.pins)
        self._changed(t_us)
