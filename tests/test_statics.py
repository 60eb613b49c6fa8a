"""Settled robot: contact loads, payload shift, tip margin."""

import numpy as np
import pytest

from amr_twin.config import load_config
from amr_twin.statics import describe, tip_margin_m


@pytest.fixture(scope="module")
def unloaded():
    return describe(load_config())


@pytest.fixture(scope="module")
def loaded():
    return describe(load_config(sets=["payload.mass_kg=20"]))


def test_contact_forces_add_up_to_weight(unloaded, loaded):
    for info in (unloaded, loaded):
        assert info["static_load_sum_n"] == pytest.approx(info["weight_n"], rel=0.01)


def test_payload_at_deck_centre_goes_to_the_wheels(unloaded, loaded):
    """Statics: the deck centre lies over the axle (x = 0), so a payload there adds no moment
    about the axle and the sprung casters' compression (set by the pitch) does not change;
    the whole 196.2 N goes to the two wheels, half each (y = 0). Tolerance 3 N per support:
    the CoM of the base robot is 6.5 mm behind the axle, and the higher total CoM
    changes the pitch equilibrium of the soft contacts by a fraction of a millimetre."""
    added = 20 * 9.81
    a, b = unloaded["static_load_n"], loaded["static_load_n"]
    for wheel in ("wheel_left", "wheel_right"):
        assert b[wheel] - a[wheel] == pytest.approx(added / 2, abs=3.0)
    for caster in ("caster_front_left", "caster_front_right", "caster_rear_left", "caster_rear_right"):
        assert b[caster] - a[caster] == pytest.approx(0.0, abs=3.0)


def test_payload_at_front_loads_front_casters():
    front = describe(load_config(sets=["payload.mass_kg=20", "payload.xy_m=[0.18,0.0]"]))
    loads = front["static_load_n"]
    assert loads["caster_front_left"] > loads["caster_rear_left"] + 20
    assert front["com_m"][0] > 0.05


def test_tip_margin_geometry():
    square = np.array([[1, 1], [-1, 1], [-1, -1], [1, -1]], float)
    assert tip_margin_m(square, np.array([0.0, 0.0])) == pytest.approx(1.0)
    assert tip_margin_m(square, np.array([0.5, 0.0])) == pytest.approx(0.5)
    assert tip_margin_m(square, np.array([1.5, 0.0])) == pytest.approx(-0.5)


def test_unloaded_tip_margin_is_positive(unloaded):
    assert 0.1 < unloaded["tip_margin_m"] < 0.3
