"""The pins taken by the plant: the drive row in force and the ``on_actuation`` hook, the fault
handles."""

from __future__ import annotations

import pytest

from amr_twin.model.config import load_config
from amr_twin.assembly.twin import Twin, TwinOptions
from amr_twin.sim.plant import MODE_CODES


@pytest.fixture()
def driving():
    twin = Twin(load_config(), TwinOptions(world="empty", nodes=()))
    twin.client.linear(0.5)
    twin.advance(0.6)
    calls = []
    twin.on_actuation(lambda t_us: calls.append((t_us, list(twin.observables.drive()))))
    return twin, calls


def test_the_drive_row_is_what_the_plant_applies(driving):
    twin, _ = driving
    pwm_l, pwm_r, dir_l, dir_r, mode_l, mode_r, volt_l, volt_r = twin.observables.drive()
    assert pwm_l > 0 and pwm_r > 0 and dir_l == dir_r == 1
    assert mode_l == mode_r == MODE_CODES["drive"]
    assert 0 < volt_l < twin.observables.battery()[0]  # a share of the terminal voltage, forward


def test_the_estop_coasts_both_wheels_and_tells_the_subscribers(driving):
    twin, calls = driving
    twin.actuation.press_estop(True, 600_000)
    assert calls[-1][0] == 600_000
    assert calls[-1][1][4:6] == [MODE_CODES["coast"]] * 2 and calls[-1][1][6:8] == [0.0, 0.0]
    twin.actuation.press_estop(False, 610_000)
    assert calls[-1][1][4:6] == [MODE_CODES["drive"]] * 2


def test_a_cut_supply_coasts_and_a_sag_lowers_the_phase_voltage(driving):
    twin, calls = driving
    twin.actuation.apply(600_000)
    before = calls[-1][1][6]  # the phase voltage at this battery state
    twin.actuation.sag_battery(3.0, 600_000)
    assert 0 < calls[-1][1][6] < 0.95 * before  # 3 V off a 30-42 V terminal: 7-10 % off the phases
    twin.actuation.sag_battery(0.0, 600_000)
    assert calls[-1][1][6] == before
    twin.actuation.cut_supply(True, 610_000)
    assert calls[-1][1][4:8] == [MODE_CODES["coast"]] * 2 + [0.0, 0.0]
