"""The plant: each wheel's driver board applies its own gain to the same firmware duty."""

from __future__ import annotations

import pytest

from amr_twin.model.config import load_config
from amr_twin.assembly.twin import Twin, TwinOptions


def _volts(sets: list[str]) -> tuple[float, float, int, int]:
    twin = Twin(load_config(sets=sets), TwinOptions(world="empty", nodes=()))
    twin.client.linear(0.5)
    twin.advance(0.8)
    pwm_l, pwm_r, _, _, _, _, volt_l, volt_r = twin.observables.drive()
    return volt_l, volt_r, pwm_l, pwm_r


@pytest.mark.parametrize("left, right", [(1.6, 1.7), (1.75, 1.55)])
def test_each_board_scales_its_own_wheel(left, right):
    """The same counts on both pins; the phase voltages stand in the ratio of the two boards'
    gains."""
    volt_l, volt_r, pwm_l, pwm_r = _volts(
        [f"driver_left.gain={left}", f"driver_right.gain={right}"]
    )
    assert pwm_l == pwm_r > 0
    assert volt_r / volt_l == pytest.approx(right / left, rel=1e-9)


def test_the_right_board_changes_only_the_right_wheel():
    base = _volts([])
    faster = _volts([f"driver_right.gain={1.2 * load_config().driver_right.gain}"])
    assert (
        faster[0] == pytest.approx(base[0], rel=1e-3) and faster[1] > base[1] * 1.1
    )  # the pack sags a little more
