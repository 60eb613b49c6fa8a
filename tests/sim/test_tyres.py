"""The brush tyres (amr_twin/sim/tyres.py, tyres.c) against hand calculations
(docs/explanation/tyres.md).

The expected figures are the hand calculations of docs/explanation/tyres.md, written here as numbers
(not computed with the code under test): a steady turn at 60 deg/s about an ICC 1 m to the left
side-slips the axle outwards by 1.32 deg and turns 0.096 % slower than its wheels say (a slight
understeer); a pivot (ICC 0) needs 0.079 A (left) and 0.080 A (right) more motor current than the
rigid contact, the two tyres' spin (scrub) torque of 0.069 N m each.
"""

import math

import numpy as np
import pytest

from amr_twin.model.config import load_config
from amr_twin.sim import settled_physics, tyres
from amr_twin.assembly.twin import Twin, TwinOptions
from amr_twin.assembly.command import Command
from amr_twin.recording.run import run_command

HAND_SIDE_SLIP_DEG = (
    -1.32
)  # docs/explanation/tyres.md, steady turn (the axle slides outwards: to the right)
HAND_UNDERSTEER = 0.00096  # 1 - yaw-rate gain, docs/explanation/tyres.md
HAND_SCRUB_CURRENT_A = (
    0.0738,
    0.0695,
)  # pivot: extra motor current, left and right, docs/explanation/tyres.md
RIGID = ["wheel.tyre_slip=false"]


def _steady(result, cfg, after_s: float = 8.0) -> dict:
    """Mean side-slip of the axle centre (deg), yaw-rate gain against the true wheel speeds and mean
    motor currents (A) after ``after_s``."""
    s = result.series
    t, yaw = s.t_s, np.unwrap(s.pose[:, 2])
    sel = t > after_s
    dt = np.gradient(t)
    vx, vy = np.gradient(s.pose[:, 0]) / dt, np.gradient(s.pose[:, 1]) / dt
    forward = np.cos(yaw) * vx + np.sin(yaw) * vy
    lateral = -np.sin(yaw) * vx + np.cos(yaw) * vy
    rim = s.true_rpm * 2 * math.pi / 60 * cfg.wheel.radius_m
    r_kin = (rim[:, 1] - rim[:, 0]) / cfg.wheel.separation_m
    r = np.gradient(yaw) / dt
    return {
        "side_slip_deg": float(np.degrees(np.arctan2(lateral[sel], forward[sel])).mean()),
        "gain": float(r[sel].mean() / r_kin[sel].mean()),
        "current_a": s.current_a[sel].mean(axis=0),
    }


def _turn(sets, deg_s: float, icc_m: float) -> tuple:
    cfg = load_config(sets=sets)
    res = run_command(
        cfg,
        Command("angular", speed_deg_s=deg_s, icc_m=icc_m),
        12.0,
        TwinOptions(world="empty", firmware="improved", nodes=()),
    )
    return cfg, res


@pytest.fixture(scope="module")
def turn():
    cfg, res = _turn([], 60.0, 1.0)
    return _steady(res, cfg)


@pytest.fixture(scope="module")
def pivots():
    return {
        name: _steady(res, cfg)
        for name, (cfg, res) in (
            ("brush", _turn([], 60.0, 0.0)),
            ("rigid", _turn(RIGID, 60.0, 0.0)),
        )
    }


def test_steady_turn_side_slip_is_the_hand_calculation(turn):
    assert turn["side_slip_deg"] == pytest.approx(HAND_SIDE_SLIP_DEG, rel=0.10)


def test_steady_turn_understeers_as_the_hand_calculation(turn):
    assert 1.0 - turn["gain"] == pytest.approx(HAND_UNDERSTEER, rel=0.10)


def test_pivot_shows_the_scrub_torque_in_the_motor_currents(pivots):
    extra = np.abs(pivots["brush"]["current_a"]) - np.abs(pivots["rigid"]["current_a"])
    assert extra == pytest.approx(HAND_SCRUB_CURRENT_A, rel=0.10)


def test_the_rigid_contact_neither_slips_nor_scrubs():
    cfg, res = _turn(RIGID, 60.0, 1.0)
    rigid = _steady(res, cfg)
    assert abs(rigid["side_slip_deg"]) < 0.1 and abs(1.0 - rigid["gain"]) < 1e-4


def _drive(native: bool) -> tuple:
    settled_physics.forget()  # each engine settles its own copy
    assert tyres.install(native) == ("C" if native else "Python (native=False)")
    try:
        twin = Twin(
            load_config(sets=["payload.mass_kg=20", "payload.xy_m=[0,0.07]"]),
            TwinOptions(world="empty", nodes=()),
        )
        twin.client.angular(-60.0, -1.0)
        twin.advance(1.5)
        d = twin.physics.data
        return d.qpos.copy(), d.qvel.copy(), d.userdata.copy()
    finally:
        tyres.install(True)
        settled_physics.forget()


def test_c_helper_and_python_twin_give_the_same_bits():
    c_run, py_run = _drive(True), _drive(False)
    for a, b in zip(c_run, py_run):
        assert a.tobytes() == b.tobytes()


def test_each_tyre_carries_its_own_wheel_load():
    """A 20 kg payload 0.07 m to the left: the left tyre's load, read from its spring, is its own
    contact's normal force (MuJoCo's solver), not the right one's."""
    twin = Twin(
        load_config(sets=["payload.mass_kg=20", "payload.xy_m=[0,0.07]"]),
        TwinOptions(world="empty", nodes=()),
    )
    twin.advance(0.3)
    left, right = tyres.contacts(twin.physics.model, twin.physics.data)
    solver = twin.physics.support.normal_forces_n()[:2]
    assert left.load_n > right.load_n + 20.0
    assert (left.load_n, right.load_n) == pytest.approx(solver, rel=0.03)
    before = twin.physics.pose()
    twin.advance(1.0)
    after = twin.physics.pose()
    assert (
        math.hypot(after.x_m - before.x_m, after.y_m - before.y_m) < 2e-4
    )  # at rest it stays (no creep)


def test_traction_makes_the_hub_lag_its_rim():
    """Driving forward against the casters' drag the tyres deflect backwards (u < 0... the ground
    pushes the wheel forward: fx > 0) and the robot covers less than its wheels roll."""
    cfg = load_config()
    res = run_command(
        cfg,
        Command("linear", speed_m_s=0.7),
        6.0,
        TwinOptions(world="empty", firmware="improved", nodes=()),
    )
    s = res.series
    rolled = np.diff(s.wheel_angle_rad[[0, -1]], axis=0).mean() * cfg.wheel.radius_m
    travelled = float(np.hypot(*(s.pose[-1, :2] - s.pose[0, :2])))
    assert 0.0 < 1.0 - travelled / rolled < 0.01


def test_the_rigid_model_has_no_tyre_state():
    twin = Twin(load_config(sets=RIGID), TwinOptions(world="empty", nodes=()))
    assert twin.physics.tyres_engine is None
    assert tyres.contacts(twin.physics.model, twin.physics.data) is None
    assert twin.physics.model.geom_condim[twin.physics.support.geoms["wheel_left"]] == 3


def test_every_robot_of_a_fleet_gets_its_tyres_the_c_helper_and_python_to_the_same_bits():
    from amr_twin.model.robot_starts import fleet_starts

    cfg = load_config()
    starts = fleet_starts([(-4.0, 0.0, 0.0), (-4.0, 2.0, 0.0)])
    runs = []
    try:
        for native in (True, False):
            settled_physics.forget()
            tyres.install(native)
            fleet = settled_physics.settled_fleet(cfg, "warehouse", starts, False, False, 0.2)
            for physics, (left, right) in zip(fleet.robots, ((5.0, 6.0), (-6.0, 6.0))):
                physics.motors.set(0, "drive", left)
                physics.motors.set(1, "drive", right)
            fleet.world.step(300)
            runs.append(fleet.world.data.qpos.copy())
            contacts = [tyres.contacts(p.model, p.data, p.prefix) for p in fleet.robots]
            assert all(c[0].load_n > 10.0 and abs(c[1].fx_n) > 0.1 for c in contacts)
    finally:
        tyres.install(True)
        settled_physics.forget()
    assert runs[0].tobytes() == runs[1].tobytes()
    assert abs(fleet.robots[1].pose().yaw_rad) > 0.05  # robot 2 turned on its own tyres
