"""Settled physics kept for the next twin: the same bits as a fresh build, never shared."""

import numpy as np
import pytest

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


# -- a world of several robots ------------------------------------------------------------------


def _fleet(poses, world="warehouse"):
    from amr_twin.model.robot_starts import fleet_starts

    return settled_mod.settled_fleet(load_config(), world, fleet_starts(poses), False, False, 0.3)


def _drive(fleet, volts, seconds):
    """Set each robot's motors to its (left, right) phase voltage, V, and step the world."""
    for physics, (left, right) in zip(fleet.robots, volts):
        for wheel, v in enumerate((left, right)):
            physics.motors.set(wheel, "drive", v)
    fleet.world.step(int(round(seconds / fleet.world.timestep_s)))
    fleet.world.check()


def test_each_robot_moves_by_its_own_command_only():
    fleet = _fleet([(0, 0, 0), (0, 2, 0)])
    one, two = fleet.robots
    assert one.data is two.data and (one.prefix, two.prefix) == ("amr-1/", "amr-2/")
    _drive(fleet, [(6.0, 6.0), (0.0, 0.0)], 1.0)  # robot 1 straight ahead, robot 2 braked
    p1, p2 = one.pose(), two.pose()
    assert p1.x_m > 0.3 and abs(p1.y_m) < 0.05 and abs(p1.yaw_rad) < 0.1
    assert abs(p2.x_m) < 1e-3 and abs(p2.y_m - 2) < 1e-3
    assert one.wheel_speeds_rad_s().min() > 1.0 and abs(two.wheel_speeds_rad_s()).max() < 0.01
    _drive(fleet, [(0.0, 0.0), (-6.0, 6.0)], 1.0)  # robot 2 turns left on the spot
    assert abs(two.pose().yaw_rad) > 0.5 and abs(two.pose().x_m) < 0.05
    assert abs(one.pose().yaw_rad - p1.yaw_rad) < 0.2  # robot 1 braked to a stop


def test_a_robot_placed_again_leaves_the_other_where_it_is():
    fleet = _fleet([(0, 0, 0), (0, 2, 0)])
    one, two = fleet.robots
    rest = one.placement.positions()
    _drive(fleet, [(0.0, 0.0), (6.0, 6.0)], 0.5)
    x2 = two.pose().x_m
    one.placement.place(1.0, -1.0, 0.0, rest)
    assert one.pose().x_m == pytest.approx(1.0) and two.pose().x_m == x2
    assert abs(two.base_velocity()[0]) > 0.1  # still rolling: its velocities untouched


def test_overlapping_starts_are_refused_naming_the_robot():
    from amr_twin.sim.start_pose import StartPoseError

    with pytest.raises(StartPoseError, match=r"^amr-1 start 0,0,0: the robot overlaps amr-2 "):
        _fleet([(0, 0, 0), (0.3, 0.1, 0)])
    with pytest.raises(StartPoseError, match=r"^amr-2 start -4,-3,0: the robot overlaps rack_s"):
        _fleet([(-4, 0, 0), (-4, -3, 0)])  # robot 2 inside the south rack
    settled_mod.forget()


def test_the_grid_loop_gives_each_robot_its_own_loop_sensor_rows():
    from amr_twin.model.robot_spec import LOOP_SENSOR_DIM
    from amr_twin.sim.grid_loop import GridLoop

    fleet = _fleet([(0, 0, 0), (0, 2, 0)])
    loop = GridLoop(fleet.world, [], 10, 1000, width=fleet.loop_width)
    for physics, v in zip(fleet.robots, (2.0, 6.0)):
        for wheel in range(2):
            physics.motors.set(wheel, "drive", v)
    _k, _ts, rows, _grid_t, _grid_rows = loop.run(0, 250)
    for i, physics in enumerate(fleet.robots):
        own = fleet.robot_rows(rows, i)
        assert all(len(row) == LOOP_SENSOR_DIM for row in own)
        named = physics.named.data.sensordata
        assert own[-1][:2] == [
            named[physics.prefix + f"wheel_{s}_angle"] for s in ("left", "right")
        ]
        assert own[-1][4:7] == named[physics.prefix + "base_pos"].tolist()
        assert own[-1][4:6] == pytest.approx([physics.pose().x_m, physics.pose().y_m], abs=1e-3)
    one, two = (fleet.robot_rows(rows, i)[-1] for i in range(2))
    assert two[0] > 2 * one[0] > 0  # robot 2 driven at three times the voltage
