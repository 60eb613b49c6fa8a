"""The lithium pack and its 10 ms accounting of what the drivers and the auxiliary load draw.

Open-circuit voltage piecewise linear in the state of charge through (0, empty),
(0.5, nominal) and (1, full), an internal resistance, and a fault's extra drop
(``sag_v``, :mod:`amr_twin.sim.fault_injector`). :meth:`Battery.account` runs on the
loop's record grid (every 10 ms): the currents drawn at that instant, each driver's
input current (``v_phase * i_phase / V_batt``, a lossless power stage, plus its
quiescent current) and the auxiliary load at constant power, drain the charge for
the time since the last call; the terminal voltage that current leaves is kept with it
(:meth:`Battery.grid_state`: the recorder's ``battery_v``, ``battery_a`` and
``battery_soc`` at every grid instant).

The accounting runs in C when a compiler is at hand (``battery.c``, built at first use by
:mod:`amr_twin.base.native_build`; measured in a 8 s run: about 13 us per 10 ms tick of
Python on the loop's cold caches); :meth:`Battery.account_python` is its Python twin,
the same operations in the same order (same bits), which the tests hold the C helper to.
The state is one ctypes struct that both read and write: :attr:`Battery.soc`,
:attr:`Battery.current_a` and :attr:`Battery.sag_v` are properties on it.

Part of the physics layer (``PHYSICS_LAYER``): its 10 ms accounting runs in C on the loop's grid,
reading the wheel speeds from MjData by address.
"""

from __future__ import annotations

import ctypes
from pathlib import Path

from amr_twin.model.config_sections import BatteryCfg
from amr_twin.sim.grid_steps import CALL2, sampler
from amr_twin.base.c_layout import register
from amr_twin.base.native_build import open_helper

PHYSICS_LAYER = True

C_SOURCE = Path(__file__).with_name("battery.c")

_D2 = ctypes.c_double * 2
_I2 = ctypes.c_int * 2
DRIVE, COAST, BRAKE = 0, 1, 2
"""Motor mode codes of :meth:`Battery.set_motor` (``amr_twin.sim.plant.MODE_CODES``)."""


class _State(ctypes.Structure):
    """``battery_state`` of battery.c."""

    _fields_ = [
        ("soc", ctypes.c_double),
        ("current_a", ctypes.c_double),
        ("sag_v", ctypes.c_double),
        ("t_last_s", ctypes.c_double),
        ("terminal_v", ctypes.c_double),
        ("empty_v", ctypes.c_double),
        ("nominal_v", ctypes.c_double),
        ("low_span_v", ctypes.c_double),
        ("high_span_v", ctypes.c_double),
        ("r_ohm", ctypes.c_double),
        ("capacity_as", ctypes.c_double),
        ("volt", _D2),
        ("mode", _I2),
        ("ke", _D2),
        ("r_ohm_motor", _D2),
        ("limit_a", _D2),
        ("brake_limit_a", ctypes.c_double),
        ("quiescent2_a", ctypes.c_double),
        ("aux_w", ctypes.c_double),
        ("dof", _I2),
        ("charger_a", ctypes.c_double),
    ]


register(C_SOURCE, battery_state=_State)


def _field(name: str, doc: str) -> property:
    def get(self) -> float:
        return getattr(self._s, name)

    def put(self, value: float) -> None:
        setattr(self._s, name, float(value))

    return property(get, put, doc=doc)


class Battery:
    """The pack (``battery:`` section of the parameter file).

    Parameters
    ----------
    cfg : BatteryCfg
    native : bool
        Account in C when the helper builds (:attr:`engine` says which runs).
    """

    soc = _field("soc", "State of charge, 1 (0 empty, 1 full).")
    current_a = _field("current_a", "The pack's current at the last accounting, A (+ discharging).")
    sag_v = _field("sag_v", "A fault's extra terminal-voltage drop, V (0 without).")
    charger_a = _field(
        "charger_a",
        "A connected charger's current limit, A (0: none): constant current, then constant "
        "voltage at ``v_full_v``.",
    )

    def __init__(self, cfg: BatteryCfg, native: bool = True):
        self.cfg = cfg
        s = self._s = _State()
        s.soc = cfg.soc_initial
        s.empty_v, s.nominal_v = cfg.v_empty_v, cfg.v_nominal_v
        s.low_span_v, s.high_span_v = (
            cfg.v_nominal_v - cfg.v_empty_v,
            cfg.v_full_v - cfg.v_nominal_v,
        )
        s.r_ohm, s.capacity_as = cfg.internal_resistance_ohm, cfg.capacity_ah * 3600.0
        s.mode[0] = s.mode[1] = COAST
        s.terminal_v = self.ocv_v()
        self._data = None
        self.account = self.account_python
        """The grid sampler ``account(t_us)``: the C helper once :meth:`connect` found it, else the
        twin."""
        self.engine = "Python (not connected)"
        self._native = native

    def ocv_v(self) -> float:
        """Open-circuit voltage at the present state of charge, V."""
        s, b = min(1.0, max(0.0, self._s.soc)), self._s
        if s < 0.5:
            return b.empty_v + b.low_span_v * s / 0.5
        return b.nominal_v + b.high_span_v * (s - 0.5) / 0.5

    def terminal_v(self) -> float:
        """Terminal voltage under the present current, V."""
        return self.ocv_v() - self._s.r_ohm * self._s.current_a - self._s.sag_v

    def draw(self, current_a: float, duration_s: float) -> None:
        """Drain ``current_a`` (negative: charge, regenerative braking) for ``duration_s``."""
        self._s.current_a = current_a
        self._s.soc -= current_a * duration_s / self._s.capacity_as

    # -- the 10 ms accounting ----------------------------------------------------------
    def connect(
        self, physics, wheel_dof, motors, brake_limit_a: float, quiescent2_a: float, aux_w: float
    ) -> None:
        """Account for two drivers and motors on ``physics`` (its MjData) from its present time on.

        ``wheel_dof``: the wheel hinges' dof addresses (2,); ``motors``: per wheel
        ``(Ke V s/rad, R ohm, current limit A)``; ``brake_limit_a``: the braking current
        limit, A; ``quiescent2_a``: both drivers' quiescent current, A; ``aux_w``: the
        auxiliary load, W.
        """
        s = self._s
        data = self._data = physics.data
        s.t_last_s = float(data.time)
        for w in range(2):
            s.dof[w] = int(wheel_dof[w])
            s.ke[w], s.r_ohm_motor[w], s.limit_a[w] = (float(v) for v in motors[w])
        s.brake_limit_a, s.quiescent2_a, s.aux_w = (
            float(brake_limit_a),
            float(quiescent2_a),
            float(aux_w),
        )
        lib, self.engine = open_helper(C_SOURCE, self._native)
        self.account = self.account_python
        if lib is not None:
            fn = lib.battery_account
            fn.restype, fn.argtypes = None, [ctypes.c_void_p, ctypes.c_void_p]
            args = (ctypes.c_void_p(data._address), ctypes.cast(ctypes.pointer(s), ctypes.c_void_p))
            self._keep = (data, args)  # the data outlives every call

            def account(t_us: int = 0, _fn=fn, _args=args) -> None:
                _fn(*_args)

            account.grid_native = sampler(
                CALL2, fn, data._address, s
            )  # the loop's grid in C calls it itself
            self.account = account

    def set_motor(self, wheel: int, mode: int, voltage_v: float) -> None:
        """Motor ``wheel``'s mode (:data:`DRIVE`, :data:`COAST`, :data:`BRAKE`) and phase voltage,
        V."""
        self._s.mode[wheel], self._s.volt[wheel] = mode, voltage_v

    def account_python(self, t_us: int = 0) -> None:
        """Drain the pack by the present current since the last call: the Python twin of
        battery.c."""
        b, d = self._s, self._data
        t = d.time
        dt = t - b.t_last_s
        b.t_last_s = t
        s = b.soc
        s = s if s > 0.0 else 0.0
        s = s if s < 1.0 else 1.0
        ocv = (
            b.empty_v + b.low_span_v * s / 0.5
            if s < 0.5
            else b.nominal_v + b.high_span_v * (s - 0.5) / 0.5
        )
        v_batt = ocv - b.r_ohm * b.current_a - b.sag_v
        v_batt = v_batt if v_batt > 1.0 else 1.0
        qvel = d.qvel
        supply = 0.0
        for w in range(2):
            mode, volt = b.mode[w], b.volt[w]
            if mode == COAST:
                i = 0.0
            else:
                limit = b.brake_limit_a if mode == BRAKE else b.limit_a[w]
                i = (volt - b.ke[w] * qvel.item(b.dof[w])) / b.r_ohm_motor[w]
                i = i if i < limit else limit
                i = i if i > -limit else -limit
            supply = volt * i if w == 0 else supply + volt * i
        current = supply / v_batt + b.quiescent2_a + b.aux_w / v_batt
        if b.charger_a > 0.0:
            head, charge = b.nominal_v + b.high_span_v - ocv, b.charger_a
            if b.r_ohm * (charge - current) > head:
                charge = head / b.r_ohm + current
            current = current - (charge if charge > 0.0 else 0.0)
        b.current_a = current
        b.soc = b.soc - current * dt / b.capacity_as
        s = b.soc
        s = s if s > 0.0 else 0.0
        s = s if s < 1.0 else 1.0
        ocv = (
            b.empty_v + b.low_span_v * s / 0.5
            if s < 0.5
            else b.nominal_v + b.high_span_v * (s - 0.5) / 0.5
        )
        b.terminal_v = ocv - b.r_ohm * current - b.sag_v

    # -- what the accounting leaves, for the recorder ---------------------------------
    def grid_state(self) -> list[float]:
        """``[terminal_v, current_a, soc]`` as the last accounting left them (V, A, 1): the
        terminal voltage at the charge left and the current drawn, minus a fault's sag."""
        s = self._s
        return [s.terminal_v, s.current_a, s.soc]

    def grid_state_addresses(self) -> list[int]:
        """Where the values of :meth:`grid_state` lie (for a C row keeper,
        ``grid_rows.gather``)."""
        base = ctypes.addressof(self._s)
        return [base + getattr(_State, name).offset for name in ("terminal_v", "current_a", "soc")]
