"""Settled physics kept for the next twin: the same bits as a fresh build, never shared."""

import numpy as np

from amr_twin.model.config import load_config
from amr_twin.sim import settled_physics as settled_mod
from amr_twin.assembly.twin import Twin, TwinOptions
from amr_twin.recording.recorder import attach_recorder, recorder_of


def _counting_builds(monkeypatch) -> list:
    calls = []
    real = settled_mod.build

    def build(*args, **kwargs):
        calls.append(args[1])
        return real(*args, **kwargs)

    monkeypatch.setattr(settled_mod, "build", build)
    return calls


def _run(cfg, options):
    twin = Twin(cfg, options)
    attach_recorder(twin)
    twin.client.linear(0.7)
    twin.advance(1.0)
    twin.client.angular(-60.0, 0.0)
    twin.advance(0.5)
    return twin


def test_a_kept_model_runs_to_the_same_bits_and_is_never_shared(monkeypatch):
    settled_mod.forget()
    builds = _counting_builds(monkeypatch)
    cfg = load_config(overrides={"payload.mass_kg": 30.0})
    options = TwinOptions(world="empty", visuals=False)
    first = _run(cfg, options)  # built; its run changes its model (rolling resistance)
    second = _run(
        load_config(overrides={"payload.mass_kg": 30.0}), options
    )  # an equal configuration: kept
    settled_mod.forget()
    third = _run(cfg, options)  # built again
    assert builds == ["empty", "empty"]
    assert (
        second.physics.model is not first.physics.model
        and second.physics.data is not first.physics.data
    )
    for twin in (second, third):
        for name in ("pose", "true_rpm", "current_a", "battery_v"):
            np.testing.assert_array_equal(
                getattr(recorder_of(first).series(), name),
                getattr(recorder_of(twin).series(), name),
                err_msg=name,
            )
        np.testing.assert_array_equal(first.physics.data.qvel, twin.physics.data.qvel)
    assert np.abs(recorder_of(first).series().pose[-1, :2]).max() > 0.15  # it drove


def test_another_configuration_or_a_world_file_is_built(monkeypatch, tmp_path):
    settled_mod.forget()
    builds = _counting_builds(monkeypatch)
    light, heavy = (load_config(overrides={"payload.mass_kg": m}) for m in (0.0, 40.0))
    a = Twin(light, TwinOptions(world="empty"))
    b = Twin(heavy, TwinOptions(world="empty"))
    c = Twin(
        light, TwinOptions(world="empty", sensors=("imu", "lidar"))
    )  # with the IMU's sensors: another model
    assert abs(b.physics.robot_mass_kg() - a.physics.robot_mass_kg() - 40.0) < 1e-9
    assert c.physics.model.nsensor == a.physics.model.nsensor + 3
    world = tmp_path / "room.xml"
    world.write_text(
        '<mujoco><worldbody><geom name="floor" type="plane" size="10 10 0.1"/></worldbody></mujoco>'
    )
    Twin(light, TwinOptions(world=str(world)))
    Twin(light, TwinOptions(world=str(world)))
    assert builds == ["empty", "empty", "empty", str(world), str(world)]
