"""The floor's friction field (amr_twin/sim/floor_friction.py) and the tyres' look-up of it.

The look-up is checked against scipy's RegularGridInterpolator on the field extended by its
repetition (not the code under test), the C helper against the Python twin bit for bit, and the
field's effect on the physics against the brush's own limit (a tyre on a patch of friction mu
gives at most mu N)."""

import math

import numpy as np
import pytest
from scipy.interpolate import RegularGridInterpolator

from amr_twin.model.config import load_config
from amr_twin.model.tyre_numeric import FIELD_CELLS, FIELD_OFFSET
from amr_twin.sim import floor_friction, settled_physics, tyres
from amr_twin.assembly.twin import Twin, TwinOptions

FIELD_ON = ["sim.floor_friction_field=true"]


def test_the_same_seed_draws_the_same_field_and_another_seed_another():
    cfg = load_config(sets=FIELD_ON)
    a, b, c = floor_friction.draw(cfg, 3), floor_friction.draw(cfg, 3), floor_friction.draw(cfg, 4)
    assert a.values.tobytes() == b.values.tobytes() and a.values.tobytes() != c.values.tobytes()
    assert a.values.shape == (FIELD_CELLS, FIELD_CELLS) and a.spacing_m == cfg.sim.floor_patch_m
    low, high = cfg.sim.floor_friction_low, cfg.wheel.friction
    assert (
        low <= a.values.min() < low + 0.05 and high - 0.05 < a.values.max() <= high
    )  # spans its range


def test_the_look_up_is_bilinear_in_x_then_y_and_repeats():
    """Random points over three periods, negative ones included, against scipy on the grid extended
    by one period each way: x indexes the columns, y the rows."""
    field = floor_friction.draw(load_config(sets=FIELD_ON), 11)
    n, h = FIELD_CELLS, field.spacing_m
    tiled = np.tile(field.values, (3, 3))  # rows y, columns x, from -n to 2n - 1 nodes
    axis = (np.arange(3 * n) - n) * h
    reference = RegularGridInterpolator((axis, axis), tiled)  # (y, x)
    data = [float(n), h, *field.values.ravel().tolist()]
    rng = np.random.default_rng(0)
    for x, y in rng.uniform(-n * h * 0.99, n * h * 1.95, (200, 2)):
        assert floor_friction.friction_at(data, x, y) == pytest.approx(
            float(reference((y, x))), abs=1e-12
        )
    assert floor_friction.friction_at(data, 0.0, 0.0) == field.values[0, 0]
    assert (
        floor_friction.friction_at(data, h, 0.0) == field.values[0, 1]
    )  # one node along x: the next column


def _pivot(field_sets, native: bool, steps_s: float = 1.5):
    settled_physics.forget()
    assert tyres.install(native) == ("C" if native else "Python (native=False)")
    try:
        twin = Twin(
            load_config(sets=FIELD_ON + field_sets),
            TwinOptions(world="empty", nodes=(), seed=7),
        )
        twin.client.angular(90.0, 0.2)
        twin.advance(steps_s)
        d = twin.physics.data
        return twin, (d.qpos.copy(), d.qvel.copy(), d.userdata.copy())
    finally:
        tyres.install(True)
        settled_physics.forget()


def test_c_helper_and_python_twin_look_the_field_up_to_the_same_bits():
    (_, c_run), (_, py_run) = _pivot([], True), _pivot([], False)
    for a, b in zip(c_run, py_run):
        assert a.tobytes() == b.tobytes()


def test_the_field_is_in_the_tyres_data_and_acts_on_them():
    twin, state = _pivot([], True, 0.5)
    (start,) = floor_friction._userdata_starts(twin.physics.model)
    start += FIELD_OFFSET
    assert (
        state[2][start] == FIELD_CELLS
        and state[2][start + 2 : start + 2 + FIELD_CELLS**2].tolist()
        == twin.floor.values.ravel().tolist()
    )
    # the same run on a field of the clean floor everywhere is the run without a field, to the bit
    flat = floor_friction.FrictionField(
        twin.floor.spacing_m, np.full((FIELD_CELLS, FIELD_CELLS), 0.8)
    )
    runs = []
    for field in (None, flat):
        t = Twin(load_config(sets=FIELD_ON), TwinOptions(world="empty", nodes=(), seed=7))
        t.physics.set_floor_friction(field)
        t.client.angular(90.0, 0.2)
        t.advance(0.5)
        runs.append(t.physics.data.qpos.tobytes())
    assert runs[0] == runs[1] and runs[0] != state[0].tobytes()


def test_a_slippery_patch_limits_the_tyre_force_to_mu_n():
    """A 0.05 field (ice) under a robot asked to spin fast: each patch gives at most mu N of
    force."""
    cfg = load_config(sets=FIELD_ON)
    twin = Twin(cfg, TwinOptions(world="empty", nodes=(), seed=1))
    twin.physics.set_floor_friction(
        floor_friction.FrictionField(0.5, np.full((FIELD_CELLS, FIELD_CELLS), 0.05))
    )
    twin.client.angular(90.0, 0.0)
    worst = 0.0
    for _ in range(20):
        twin.advance(0.05)
        for c in tyres.contacts(twin.physics.model, twin.physics.data):
            worst = max(worst, math.hypot(c.fx_n, c.fy_n) / c.load_n)
    assert 0.03 < worst <= 0.05 + 1e-9


def test_rigid_contact_has_no_field():
    twin = Twin(
        load_config(sets=FIELD_ON + ["wheel.tyre_slip=false"]),
        TwinOptions(world="empty", nodes=()),
    )
    assert twin.floor is None
    with pytest.raises(ValueError, match="no brush tyres"):
        twin.physics.set_floor_friction(floor_friction.draw(twin.cfg, 0))
