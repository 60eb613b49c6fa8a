"""Collisions of the robot with the world: detected, reported, stopped on; start poses refused."""

import json

import pytest
from typer.testing import CliRunner

from amr_twin.cli.main import app
from amr_twin.model.config import load_config
from amr_twin.assembly.twin import Twin, TwinOptions
from amr_twin.assembly.command import Command
from amr_twin.recording.run import run_command

CFG = load_config()
runner = CliRunner()

KERB = """<mujoco model="kerb">
  <worldbody>
    <geom name="floor" type="plane" size="10 10 0.1"/>
    <geom name="kerb" type="box" pos="1.5 0 0.02" size="0.05 2 0.02"/>
  </worldbody>
</mujoco>
"""


def _json(*args):
    res = runner.invoke(app, ["run", *args, "--json"])
    return res, (json.loads(res.stdout) if res.stdout.strip().startswith("{") else None)


def test_wheels_and_casters_on_the_floor_are_not_collisions():
    result = run_command(
        CFG, Command("angular", speed_deg_s=90, icc_m=0), 4.0, TwinOptions(world="empty")
    )
    assert result.collisions == [] and not result.halted


def test_the_default_start_has_room_for_half_a_metre_per_second_for_20_s():
    res, info = _json("linear", "--speed-m-s", "0.5", "--duration-s", "20")
    assert res.exit_code == 0 and info["collisions"] == [] and "warning" not in res.stderr
    assert info["start_pose"] == {"x_m": -6.0, "y_m": 0.0, "yaw_rad": 0.0}
    assert info["final_pose"]["x_m"] > 3.0  # drove about 10 m down the aisle


def test_a_veering_run_reports_the_rack_it_hits_with_time_and_place():
    res, info = _json("linear", "--speed-m-s", "0.7", "--duration-s", "9")
    assert res.exit_code == 0
    (hit,) = info["collisions"]
    assert hit["hit"] == "rack_s_beam_low" and "base_link" in hit["robot_parts"]
    assert 6.0 < hit["t_s"] < 8.0 and hit["y_m"] == pytest.approx(
        -2.96, abs=0.02
    )  # the beam's north face
    assert hit["until_s"] > hit["t_s"] and hit["peak_force_n"] > 10.0
    assert "warning: collision at t = " in res.stderr and "rack_s_beam_low" in res.stderr


def test_stop_on_collision_ends_the_run_there_with_exit_code_4():
    res, info = _json("linear", "--speed-m-s", "0.7", "--duration-s", "9", "--stop-on-collision")
    assert res.exit_code == 4 and info["stopped_by_collision"]
    assert info["sim_s"] == pytest.approx(info["collisions"][0]["t_s"], abs=1e-9)
    assert info["sim_s"] < 8.0


def test_a_low_kerb_is_hit_by_a_wheel_or_caster(tmp_path):
    world = tmp_path / "kerb.xml"
    world.write_text(KERB)
    result = run_command(CFG, Command("linear", speed_m_s=0.4), 5.0, TwinOptions(world=str(world)))
    assert result.collisions, "the kerb was not reported"
    first = result.collisions[0]
    assert first["hit"] == "kerb" and first["x_m"] == pytest.approx(1.45, abs=0.06)
    assert any(p.startswith(("caster_", "wheel_")) for p in first["robot_parts"])
    # the kerb lies across the path (4 m long): both front casters meet it, within one episode
    # of contact with it, which names every part involved (a dropped second part once survived)
    assert len(result.collisions) == 1
    assert {"caster_front_left_link", "caster_front_right_link"} <= set(first["robot_parts"])


def test_collisions_and_faults_are_in_the_recordings(tmp_path):
    from rerun.chunk import RrdReader
    from rosbags.rosbag2 import Reader
    from rosbags.typesys import Stores, get_typestore

    mcap, rrd = tmp_path / "c.mcap", tmp_path / "c.rrd"
    res, info = _json(
        "linear",
        "--speed-m-s",
        "0.7",
        "--duration-s",
        "7.5",
        "--fault",
        "estop@7.3",
        "--mcap",
        str(mcap),
        "--record",
        str(rrd),
    )
    assert res.exit_code == 0 and len(info["collisions"]) == 1
    store = get_typestore(Stores.ROS2_HUMBLE)  # ROS 2's own definitions, not ours
    seen = {}
    with Reader(mcap) as reader:
        for con, t_ns, raw in reader.messages():
            if con.topic in ("/twin/collisions", "/twin/faults"):
                status = store.deserialize_cdr(raw, con.msgtype).status[0]
                seen[con.topic] = (
                    t_ns,
                    status.level,
                    status.message,
                    {kv.key: kv.value for kv in status.values},
                )
    t_ns, level, message, values = seen["/twin/collisions"]
    assert level == 2 and "rack_s_beam_low" in message
    assert t_ns == round(info["collisions"][0]["t_s"] * 1e9) and float(
        values["y_m"]
    ) == pytest.approx(-2.96, abs=0.02)
    assert seen["/twin/faults"][0] == 7_300_000_000 and seen["/twin/faults"][1] == 1
    paths = {str(c.entity_path) for c in RrdReader(str(rrd)).stream().to_chunks()}
    assert {"/events/collisions", "/events/faults", "/world/collisions"} <= paths


def test_c_pair_check_and_python_give_the_same_episodes(monkeypatch):
    """The veering run that scrapes a rack, then a spin against it: the same episodes either way."""
    import functools
    import shutil

    import amr_twin.assembly.world as loop_mod
    from amr_twin.sim.collisions import CollisionMonitor

    if shutil.which("cc") is None and shutil.which("gcc") is None:
        pytest.skip("no C compiler")
    out = []
    for native in (True, False):
        monkeypatch.setattr(
            loop_mod, "CollisionMonitor", functools.partial(CollisionMonitor, native=native)
        )
        twin = Twin(CFG, TwinOptions(start_xy_yaw=None))
        twin.client.linear(0.7)
        twin.advance(8.5)
        twin.client.angular(90.0, 0.0)
        twin.advance(1.5)
        out.append((twin.collisions.engine, twin.collisions.as_dicts()))
    (c_engine, c_hits), (py_engine, py_hits) = out
    assert c_engine == "C" and py_engine == "Python (native=False)"
    assert c_hits == py_hits and len(c_hits) >= 1 and c_hits[0]["hit"] == "rack_s_beam_low"


def test_the_c_pair_check_sees_any_change_of_the_pairs():
    """One contact each time, on the same floor: a ball resting there, then another one instead."""
    import ctypes
    import shutil

    import mujoco

    from amr_twin.base import native_build
    from amr_twin.sim.collisions import C_SOURCE, _Memo

    if shutil.which("cc") is None and shutil.which("gcc") is None:
        pytest.skip("no C compiler")
    m = mujoco.MjModel.from_xml_string("""<mujoco><worldbody>
      <geom name="floor" type="plane" size="5 5 .1"/>
      <body><freejoint/><geom name="a" type="sphere" size=".1"/></body>
      <body><freejoint/><geom name="b" type="sphere" size=".1"/></body></worldbody></mujoco>""")
    d = mujoco.MjData(m)
    fn = native_build.load_helper(C_SOURCE).contacts_changed
    fn.restype, fn.argtypes = ctypes.c_int, [ctypes.c_void_p, ctypes.c_void_p]
    memo, pairs = _Memo(), (ctypes.c_int * 8)()
    memo.cap, memo.pairs = 4, pairs

    def changed(a_z, b_z, valid=True):
        d.qpos[:7], d.qpos[7:] = [0, 0, a_z, 1, 0, 0, 0], [1, 0, b_z, 1, 0, 0, 0]
        mujoco.mj_forward(m, d)
        out = fn(d._address, ctypes.addressof(memo))
        memo.valid = int(valid)
        return out, d.contact.geom.tolist()

    assert changed(0.099, 1.0) == (1, [[0, 1]])  # nothing kept yet
    assert changed(0.098, 1.0)[0] == 0  # the same pair
    assert changed(1.0, 0.099) == (1, [[0, 2]])  # the same count and first geom, another ball
    assert changed(0.099, 0.099)[0] == 1  # both
    assert changed(0.099, 0.099, valid=False)[0] == 0
    assert changed(0.099, 0.099)[0] == 1  # invalidated by the monitor: classified again
    assert changed(1.0, 1.0)[0] == 1 and changed(1.0, 1.0)[0] == 0  # none, then none again


def test_two_robots_driven_head_on_collide_and_each_monitor_names_the_other():
    import math

    from amr_twin.model.robot_starts import fleet_starts
    from amr_twin.sim.collisions import CollisionMonitor
    from amr_twin.sim.grid_loop import GridLoop
    from amr_twin.sim.settled_physics import settled_fleet

    starts = fleet_starts([(-4.0, 0.0, 0.0), (-1.0, 0.0, math.pi), (-4.0, 2.0, 0.0)])
    fleet = settled_fleet(CFG, "warehouse", starts, False, False, 0.3)
    monitors = [CollisionMonitor(physics) for physics in fleet.robots]
    loop = GridLoop(fleet.world, monitors, 10, 1000, width=fleet.loop_width)
    for physics in fleet.robots[:2]:  # robots 1 and 2 ahead at 6 V, robot 3 braked
        for wheel in range(2):
            physics.motors.set(wheel, "drive", 6.0)
    loop.run(0, 3000)
    (one,), (two,) = (m.as_dicts() for m in monitors[:2])
    assert (one["robot"], one["hit"], two["robot"], two["hit"]) == (
        "amr-1",
        "amr-2",
        "amr-2",
        "amr-1",
    )
    assert 0.8 < one["t_s"] == two["t_s"] < 2.5 and one["peak_force_n"] > 10.0
    assert -3.0 < one["x_m"] < -2.0  # where they met, half way
    assert monitors[2].collisions == []
