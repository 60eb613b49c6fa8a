"""Rolling resistance: the C helper and its Python twin give the same bits; the loads it acts on."""

import functools
import os
import shutil
import subprocess
import sys

import numpy as np
import pytest

import amr_twin.assembly.robot as loop_mod
from amr_twin.model.config import load_config
from amr_twin.base import native_build
from amr_twin.assembly.twin import Twin, TwinOptions
from amr_twin.sim.rolling_resistance import C_SOURCE, RollingResistance


def _drive(monkeypatch, cfg, native: bool):
    monkeypatch.setattr(
        loop_mod, "RollingResistance", functools.partial(RollingResistance, native=native)
    )
    twin = Twin(cfg, TwinOptions(world="warehouse"))
    twin.client.linear(0.7)
    twin.advance(2.0)
    twin.client.angular(-60.0, 0.0)  # spin in place: the balls' forces turn with the chassis
    twin.advance(2.0)
    twin.client.stop()
    twin.advance(1.5)
    d = twin.physics.data
    return (
        twin.rolling.engine,
        d.qpos.copy(),
        d.qvel.copy(),
        twin.plant.battery.soc,
        twin.rolling.loads,
    )


@pytest.mark.skipif(
    shutil.which("cc") is None and shutil.which("gcc") is None, reason="no C compiler"
)
@pytest.mark.parametrize("payload_kg", [0.0, 40.0])
def test_c_helper_and_python_twin_give_the_same_bits(monkeypatch, payload_kg):
    cfg = load_config(overrides={"payload.mass_kg": payload_kg, "payload.xy_m": [-0.15, 0.05]})
    c_engine, *c_state = _drive(monkeypatch, cfg, native=True)
    py_engine, *py_state = _drive(monkeypatch, cfg, native=False)
    assert c_engine == "C", c_engine  # a compiler is here: the helper must build and load
    assert py_engine.startswith("Python")
    for a, b in zip(c_state, py_state):
        assert np.array_equal(np.asarray(a), np.asarray(b))


@pytest.mark.skipif(
    shutil.which("cc") is None and shutil.which("gcc") is None, reason="no C compiler"
)
def test_contact_loads_of_the_helper_are_the_physics_contact_forces():
    """rr_contact_loads (a sweep point's 50 Hz sample) gives Support.normal_forces_n's bits:
    the wheels' and balls' normal contact forces, each support on its own, through a turn with
    a payload at the rear that unloads the front casters."""
    cfg = load_config(overrides={"payload.mass_kg": 45.0, "payload.xy_m": [-0.2, 0.07]})
    twin = Twin(cfg, TwinOptions(world="empty", visuals=False))
    assert twin.rolling.engine == "C"
    seen = []

    def sample(t_us):
        seen.append((twin.rolling.contact_loads(), twin.physics.support.normal_forces_n().tolist()))

    twin.samplers.append(sample)
    twin.client.linear(0.7)
    twin.advance(1.0)
    twin.client.angular(-60.0, 0.0)
    twin.advance(1.0)
    c, py = np.array([a for a, _ in seen]), np.array([b for _, b in seen])
    assert len(seen) >= 200 and np.array_equal(c, py)
    weight = cfg.payload.mass_kg * cfg.sim.gravity_m_s2
    assert (
        np.all(c[:, :2] > 50.0) and c.sum(axis=1).mean() > weight
    )  # the robot and its load stand on them
    assert (
        c[:, 2:4].mean() < c[:, 4:].mean()
    )  # rear payload: the rear casters carry more than the front


def test_resistance_follows_the_loads(monkeypatch):
    """Tyre: the hinge friction grows by Crr N r; balls: Crr N against the ball's motion."""
    cfg = load_config(overrides={"payload.mass_kg": 30.0})
    twin = Twin(cfg, TwinOptions(world="empty"))
    twin.client.linear(0.5)
    twin.advance(2.0)
    m, d, rr = twin.physics.model, twin.physics.data, twin.rolling
    rr.update(0)
    loads = rr.loads
    arm = cfg.wheel.rolling_resistance * cfg.wheel.radius_m
    assert arm > 0 and min(loads[:2]) > 100  # 30 kg on board: both tyres carry well over 100 N
    for w, dof in enumerate(twin.physics.wheel_dof):
        motor = (cfg.motor_left, cfg.motor_right)[w]
        assert m.dof_frictionloss[dof] == pytest.approx(
            motor.friction_nm + arm * loads[w], rel=1e-12
        )
    rr.update(0)
    # driving straight ahead (+x in the body frame): the balls pull back with Crr times their load
    fx_body = d.qfrc_applied[twin.physics.root_dof]
    yaw = twin.physics.pose().yaw_rad
    f_back = -(np.cos(yaw) * fx_body + np.sin(yaw) * d.qfrc_applied[twin.physics.root_dof + 1])
    assert f_back == pytest.approx(cfg.caster.rolling_resistance * sum(loads[2:]), rel=0.02)
    assert sum(loads) == pytest.approx(
        (twin.physics.model.body_subtreemass[1]) * cfg.sim.gravity_m_s2, rel=0.03
    )


def test_without_a_helper_the_python_twin_runs_and_says_why(tmp_path):
    broken = tmp_path / "broken.c"
    broken.write_text("this is not C\n")
    status = native_build.native_status(broken)
    assert status.startswith("Python (broken.c did not compile"), status
    code = (
        "from amr_twin.model.config import load_config; from amr_twin.assembly.twin import Twin; "
        "print(Twin(load_config()).rolling.engine)"
    )
    env = {**os.environ, "AMR_TWIN_NATIVE": "0"}
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, env=env, check=True
    )
    assert out.stdout.strip() == "Python (AMR_TWIN_NATIVE=0)"
    assert C_SOURCE.exists()


@pytest.mark.skipif(
    shutil.which("cc") is None and shutil.which("gcc") is None, reason="no C compiler"
)
def test_a_damaged_build_is_replaced(tmp_path):
    """A built helper that does not load is removed, so that the next process builds it again."""
    source = tmp_path / "helper.c"
    source.write_text("int answer(void) { return 42; }\n")
    code = (
        "import sys; from pathlib import Path; from amr_twin.base import native_build as nb; "
        "s = Path(sys.argv[1]); lib = nb.load_helper(s); print(nb.native_status(s), lib.answer() "
        "if lib else '-')"
    )
    env = {**os.environ, "AMR_TWIN_CACHE_DIR": str(tmp_path / "cache")}

    def status():
        out = subprocess.run(
            [sys.executable, "-c", code, str(source)],
            capture_output=True,
            text=True,
            env=env,
            check=True,
        )
        return out.stdout.strip()

    assert status() == "C 42"
    (built,) = (tmp_path / "cache" / "native").glob("helper-*.so")
    built.write_bytes(b"not a shared object")
    assert status().startswith("Python (helper-")  # falls back, and removes it
    assert not built.exists()
    assert status() == "C 42"  # built again
