"""The firmware registry: the built-in kinds by name, a third party's own, the one-line refusal."""

from __future__ import annotations

import numpy as np
import pytest

from amr_twin.controllers.firmware import FIRMWARES, firmware_kind, make_firmware
from amr_twin.controllers.improved import ImprovedFirmware, ImprovedParams
from amr_twin.model.config import load_config
from amr_twin.recording.recorder import attach_recorder
from amr_twin.base.clock import VirtualClock
from amr_twin.assembly.twin import Twin, TwinOptions

CALLS = []


def improved_copy(clock, publish, params, *, edges_per_rev, sketch):
    """A third party's firmware: the improved one, built through the registry."""
    CALLS.append((edges_per_rev, sketch))
    return ImprovedFirmware(clock, publish, edges_per_rev, params or ImprovedParams())


@pytest.fixture
def registered():
    FIRMWARES.register("improved_copy", improved_copy)
    CALLS.clear()
    yield
    FIRMWARES.unregister("improved_copy")


def test_the_built_in_kinds_are_registered_in_order():
    assert FIRMWARES.names()[:3] == ("faithful", "improved", "avr")
    firmware = make_firmware("improved", VirtualClock(), lambda *_: None, edges_per_rev=90)
    assert type(firmware) is ImprovedFirmware


def test_an_unknown_kind_is_refused_in_one_line_naming_the_choices():
    with pytest.raises(
        ValueError, match=r"^--firmware 'avx': must be one of faithful, improved or avr"
    ):
        firmware_kind("avx")
    with pytest.raises(ValueError, match=r"^--firmware 'avx': must be one of"):
        make_firmware("avx", VirtualClock(), lambda *_: None, edges_per_rev=90)


def _series(firmware: str):
    cfg = load_config()
    twin = Twin(cfg, TwinOptions(firmware=firmware, world="empty", visuals=False))
    recorder = attach_recorder(twin)
    twin.client.linear(0.5)
    twin.advance(2.0)
    return recorder.series()


def test_a_registered_firmware_is_a_kind_the_twin_runs(registered):
    assert firmware_kind("improved_copy") == "improved_copy"
    mine, improved, faithful = _series("improved_copy"), _series("improved"), _series("faithful")
    assert CALLS == [(load_config().wheel.sc_edges_per_rev, None)]
    np.testing.assert_array_equal(mine.pwm_counts, improved.pwm_counts)
    assert not np.array_equal(mine.pwm_counts, faithful.pwm_counts)  # the kind decides the drive
