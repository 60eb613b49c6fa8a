"""The battery's 10 ms accounting: what it drains, and the C helper against its Python twin."""

import functools
import shutil

import numpy as np
import pytest

import amr_twin.sim.plant as plant_mod
from amr_twin.model.config import load_config
from amr_twin.sim.battery import Battery
from amr_twin.sim.faults import parse_faults
from amr_twin.assembly.twin import Twin, TwinOptions
from amr_twin.recording.recorder import attach_recorder, recorder_of

HAVE_CC = shutil.which("cc") is not None or shutil.which("gcc") is not None


def _twin(monkeypatch, cfg, native: bool, **options) -> Twin:
    monkeypatch.setattr(plant_mod, "Battery", functools.partial(Battery, native=native))
    twin = Twin(cfg, TwinOptions(world="empty", **options))
    attach_recorder(twin)
    return twin


def _ocv_v(cfg, soc: np.ndarray) -> np.ndarray:
    """The pack's open-circuit voltage by its definition in the parameter file: linear through
    (0, empty), (0.5, nominal), (1, full)."""
    b = cfg.battery
    return np.interp(soc, [0.0, 0.5, 1.0], [b.v_empty_v, b.v_nominal_v, b.v_full_v])


@pytest.mark.parametrize("native", [True, False])
def test_at_rest_it_drains_the_quiescent_and_auxiliary_current(monkeypatch, native):
    """Standing still, the pack gives 2 quiescent currents and the auxiliary power at its terminal
    voltage: I = 2 Iq + P / V, V = OCV(soc) - R I, solved here by hand (a quadratic in V). At rest
    nothing changes but the charge (1e-4 of it in 20 s), so the 10 ms the accounting's voltage lags
    its current is worth about 1e-9 of it: the tolerances are 1e-7 and 1e-4 (the R I
    drop, 0.1-0.3 % of the current, hid inside the former 0.1 %)."""
    cfg = load_config()
    twin = _twin(monkeypatch, cfg, native)
    b = twin.plant.battery
    soc0 = b.soc
    twin.advance(20.0)
    r, q, p = (
        cfg.battery.internal_resistance_ohm,
        2 * cfg.driver.quiescent_current_a,
        cfg.battery.auxiliary_power_w,
    )
    ocv = float(_ocv_v(cfg, b.soc))
    v = (ocv - r * q + np.sqrt((ocv - r * q) ** 2 - 4 * r * p)) / 2  # V^2 - (OCV - R q) V + R P = 0
    expected_a = q + p / v
    assert b.current_a == pytest.approx(expected_a, rel=1e-7)
    assert b.terminal_v() == pytest.approx(v, rel=1e-9)
    assert soc0 - b.soc == pytest.approx(
        expected_a * 20.0 / (cfg.battery.capacity_ah * 3600), rel=1e-4
    )


def test_battery_voltage_is_recorded_at_every_grid_instant(monkeypatch):
    """The terminal voltage follows the current between pin changes (it was held from one
    pin change to the next: 39.505 V to 8.55 s while the current fell at 8.05 s). Every row: V =
    OCV(soc) - R I, and the state of charge drains by the current over each 10 ms."""
    cfg = load_config(overrides={"payload.mass_kg": 20.0})
    twin = _twin(monkeypatch, cfg, True)
    twin.client.linear(0.7)
    twin.advance(6.0)
    twin.client.stop()
    twin.advance(3.0)
    s = recorder_of(twin).series()
    ocv = _ocv_v(cfg, s.battery_soc)
    np.testing.assert_allclose(
        s.battery_v, ocv - cfg.battery.internal_resistance_ohm * s.battery_a, rtol=0, atol=1e-9
    )
    drained = -np.diff(s.battery_soc) * cfg.battery.capacity_ah * 3600  # A s per interval
    np.testing.assert_allclose(drained, s.battery_a[1:] * np.diff(s.t_s), rtol=1e-9, atol=1e-15)
    pins = np.column_stack([s.pwm_counts, s.direction, s.mode])
    same_pins = np.all(pins[1:] == pins[:-1], axis=1)
    moved = np.abs(np.diff(s.battery_v)) > 1e-6
    assert (
        np.count_nonzero(same_pins & moved) > 100
    )  # the voltage moves with the current, pins or not
    assert s.battery_v.max() - s.battery_v.min() > 0.1


def test_driving_draws_the_motors_power_from_the_pack(monkeypatch):
    """At 0.7 m/s the pack's current exceeds the rest current by the motors' electrical power over
    V."""
    cfg = load_config(overrides={"payload.mass_kg": 30.0})
    twin = _twin(monkeypatch, cfg, True)
    twin.client.linear(0.7)
    twin.advance(4.0)
    s = recorder_of(twin).series()
    late = s.t_s > 3.0
    rest_a = 2 * cfg.driver.quiescent_current_a + cfg.battery.auxiliary_power_w / s.battery_v[late]
    motors_w = (s.voltage_v[late] * s.current_a[late]).sum(axis=1)
    assert np.all(motors_w > 5.0)  # rolling a 30 kg payload takes power
    assert np.allclose(s.battery_a[late], rest_a + motors_w / s.battery_v[late], rtol=0.02)


@pytest.mark.skipif(not HAVE_CC, reason="no C compiler")
def test_c_helper_and_python_twin_give_the_same_bits(monkeypatch):
    """Drive, brake, coast (a cut supply) and a sagging pack: the same charge and currents to the
    bit."""
    cfg = load_config(overrides={"payload.mass_kg": 20.0})
    faults = parse_faults(["battery-sag@1:drop_v=6,for=1.5", "battery-cut@3.5:for=0.5"])
    out = []
    for native in (True, False):
        twin = _twin(monkeypatch, cfg, native, faults=faults)
        twin.client.linear(0.6)
        twin.advance(3.0)
        twin.client.stop()
        twin.advance(2.0)
        s, b = recorder_of(twin).series(), twin.plant.battery
        out.append(
            (
                b.engine,
                b.soc,
                b.current_a,
                s.battery_v.tobytes(),
                s.battery_a.tobytes(),
                s.battery_soc.tobytes(),
                twin.physics.data.qpos.tobytes(),
            )
        )
    (c_engine, *c_state), (py_engine, *py_state) = out
    assert c_engine == "C" and py_engine == "Python (native=False)"
    assert c_state == py_state


@pytest.mark.skipif(not HAVE_CC, reason="no C compiler")
def test_c_helper_and_python_twin_agree_on_every_branch():
    """Random modes, voltages, wheel speeds past both current limits, charge outside 0-1, a sag, a
    charger (its constant-current and constant-voltage branches)."""
    from amr_twin.model.build import build
    from amr_twin.sim.physics import Physics
    from amr_twin.sim.plant import Plant

    cfg = load_config()
    physics = Physics(build(cfg, world="empty").model)
    plants = [
        Plant(
            physics,
            cfg.driver,
            (cfg.driver_left, cfg.driver_right),
            (cfg.motor_left, cfg.motor_right),
            cfg.battery,
        )
        for _ in range(2)
    ]
    native, python = (p.battery for p in plants)
    native_account, python_account = native.account, python.account_python
    assert native.engine == "C"
    rng = np.random.default_rng(3)
    d = physics.data
    for _ in range(500):
        modes, volts = rng.integers(0, 3, 2), rng.uniform(-40.0, 40.0, 2)
        speeds, soc, sag = (
            rng.uniform(-60.0, 60.0, 2),
            rng.uniform(-0.2, 1.2),
            rng.choice([0.0, 5.0]),
        )
        d.qvel[list(physics.wheel_dof)] = speeds
        d.time += rng.uniform(0.0, 0.02)
        charger = rng.choice([0.0, 4.0, 10.0])
        for b in (native, python):
            b.soc, b.sag_v, b.charger_a = soc, sag, charger
            for w in range(2):
                b.set_motor(w, int(modes[w]), float(volts[w]))
        native_account()
        python_account()
        assert native.grid_state() == python.grid_state()  # terminal voltage, current, charge
    assert np.isfinite(native.soc)


@pytest.mark.parametrize("native", [True, False])
def test_a_charger_fills_the_pack_at_its_current_then_holds_it_at_full_voltage(monkeypatch, native):
    """Standing, a 4 A charger: the pack takes 4 A less the rest current (the charger feeds the
    auxiliary load too) and its charge rises by that over 10 s; near full the charger holds the
    terminals at v_full_v (constant voltage) and the current tapers off."""
    cfg = load_config()
    twin = _twin(monkeypatch, cfg, native)
    b = twin.plant.battery
    twin.advance(1.0)
    rest_a, soc0 = b.current_a, b.soc
    twin.set_charger_a(cfg.battery.charge_current_a)
    twin.advance(10.0)
    rest_now = 2 * cfg.driver.quiescent_current_a + cfg.battery.auxiliary_power_w / b.terminal_v()
    assert b.current_a == pytest.approx(rest_now - cfg.battery.charge_current_a, abs=1e-4)
    assert b.soc - soc0 == pytest.approx(
        (cfg.battery.charge_current_a - rest_a) * 10.0 / (cfg.battery.capacity_ah * 3600), rel=3e-3
    )
    b.soc = 0.9995
    twin.advance(5.0)
    assert b.terminal_v() == pytest.approx(cfg.battery.v_full_v, abs=1e-3)
    assert -cfg.battery.charge_current_a < b.current_a < 0.0 and 0.9995 < b.soc < 1.0
    twin.set_charger_a(0.0)
    twin.advance(1.0)
    assert b.current_a > 0.0 and b.terminal_v() < cfg.battery.v_full_v
