"""Start poses: one inside an obstacle or over no floor is refused; the stand holds the robot."""

import json
import math

import pytest
from typer.testing import CliRunner

from amr_twin.cli.main import app
from amr_twin.model.config import load_config
from amr_twin.assembly.twin import Twin, TwinOptions
from amr_twin.sim.start_pose import StartPoseError

CFG = load_config()
runner = CliRunner()


def _json(*args):
    res = runner.invoke(app, ["run", *args, "--json"])
    return res, (json.loads(res.stdout) if res.stdout.strip().startswith("{") else None)


def test_a_start_inside_a_rack_or_without_a_floor_is_refused(tmp_path):
    with pytest.raises(StartPoseError, match="overlaps rack_n_beam_low"):
        Twin(CFG, TwinOptions(start_xy_yaw=(-2.5, 3.0, 0.0)))
    (tmp_path / "void.xml").write_text(
        '<mujoco><worldbody><light pos="0 0 3"/></worldbody></mujoco>'
    )
    res = runner.invoke(
        app, ["run", "linear", "--speed-m-s", "0.5", "--world", str(tmp_path / "void.xml")]
    )
    assert (
        res.exit_code == 2
        and "no floor" in res.stderr
        and len(res.stderr.strip().splitlines()) == 1
    )
    res = runner.invoke(app, ["run", "stop", "--start=10,0,0"])
    assert res.exit_code == 2 and "--start 10,0,0" in res.stderr and "wall_east" in res.stderr


def test_a_start_overlapping_many_geoms_names_five_and_counts_the_rest(tmp_path):
    """A map of many small walls under the robot: the refusal stays a short line (was every
    name)."""
    boxes = "".join(
        f'<geom name="post_{i}" type="box" size="0.02 0.02 0.3" pos="{-0.3 + 0.06 * i:.2f} 0 0.3"/>'
        for i in range(9)
    )
    (tmp_path / "posts.xml").write_text(
        '<mujoco><worldbody><geom name="floor" type="plane" size="5 5 0.1"/>'
        f"{boxes}</worldbody></mujoco>"
    )
    res = runner.invoke(app, ["run", "stop", "--world", str(tmp_path / "posts.xml")])
    assert res.exit_code == 2, res.output
    (line,) = res.stderr.strip().splitlines()
    assert "post_0, post_1, post_2, post_3, post_4 and 4 more there" in line, line


def test_the_stand_holds_the_robot_and_gives_the_bench_point():
    """The README's bench-point command: the stand world's weld holds the chassis
    (fig. 5.1), so the start check lets it run with no wheel on the floor, and the free left
    wheel at listing 4.1's 71.5 RPM draws about its "0,38 Amp" of motor current."""
    res, info = _json(
        "motor",
        "--wheel",
        "left",
        "--direction",
        "forward",
        "--speed-m-s",
        "0.936",
        "--world",
        "stand",
    )
    assert res.exit_code == 0, res.stderr
    left, right = info["wheels"]["left"], info["wheels"]["right"]
    assert left["reference_rpm"] == pytest.approx(71.5, abs=0.01)
    assert 0.34 < left["current_a_final"] < 0.42  # 0.38 A +- the calibration's 0.04 A
    # steady and free, the motor's torque Ke I balances its friction and damping at its speed
    m = CFG.motor_left
    w = left["true_final_rpm"] * math.pi / 30
    assert left["current_a_final"] == pytest.approx(
        (m.friction_nm + m.damping_nm_s_rad * w) / m.ke_v_s_rad, rel=0.01
    )
    assert (
        abs(right["true_final_rpm"]) < 0.1 and right["current_a_peak"] < 0.01
    )  # the other wheel idles
    pose = info["final_pose"]
    assert (
        math.hypot(pose["x_m"], pose["y_m"]) < 0.01 and abs(pose["yaw_rad"]) < 0.01
    )  # held where it stands
    assert info["collisions"] == []
