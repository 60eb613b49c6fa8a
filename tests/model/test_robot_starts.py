"""Robot starts: fleet names, the bad inputs refused in one line, N robots built into one model."""

import math

import mujoco
import pytest

from amr_twin.model.build import build
from amr_twin.model.config import load_config
from amr_twin.model.robot_starts import MAX_ROBOTS, ROBOT_PREFIX, fleet_starts
from amr_twin.model.tyre_numeric import numeric_ids


def test_one_start_is_the_lone_robot_several_are_numbered_in_order():
    (lone,) = fleet_starts([(1, 2, 0.5)])
    assert (lone.prefix, lone.x_m, lone.y_m, lone.yaw_rad) == (ROBOT_PREFIX, 1.0, 2.0, 0.5)
    fleet = fleet_starts([(0, 0, 0), (2, 0, math.pi), (4, 1, 0)])
    assert [s.prefix for s in fleet] == ["amr-1/", "amr-2/", "amr-3/"]
    assert [s.name for s in fleet] == ["amr-1", "amr-2", "amr-3"]
    assert fleet[1].x_m == 2.0


@pytest.mark.parametrize(
    "poses, says",
    [
        ([], "0 start poses; 1 to 20"),
        ([(0, 0, 0)] * (MAX_ROBOTS + 1), "21 start poses"),
        ([(0, 0, 0), (1, 0)], "start 2 is (1, 0)"),
        ([(0, 0, 0), (1, float("nan"), 0)], "start 2"),
    ],
)
def test_bad_starts_are_refused_in_one_line_naming_the_start(poses, says):
    with pytest.raises(ValueError) as err:
        fleet_starts(poses)
    assert says in str(err.value) and "\n" not in str(err.value)


def test_each_robot_is_built_at_its_pose_under_its_prefix_with_its_own_tyres():
    cfg = load_config()
    starts = fleet_starts([(0, 0, 0), (2, 1, math.pi / 2)])
    m = build(cfg, "warehouse", robots=starts).model
    d = mujoco.MjData(m)
    mujoco.mj_forward(m, d)
    for s in starts:
        base = d.body(s.prefix + "base_link")
        assert base.xpos[:2].tolist() == pytest.approx([s.x_m, s.y_m], abs=1e-9)
        assert math.atan2(base.xmat[3], base.xmat[0]) == pytest.approx(s.yaw_rad, abs=1e-9)
    ids = numeric_ids(m)
    assert [m.numeric(i).name for i in ids] == ["amr_tyres:amr-1/", "amr_tyres:amr-2/"]
    userdata = [int(m.numeric_data[m.numeric_adr[i] + 1]) for i in ids]
    assert userdata[0] != userdata[1]  # each robot's tyre states in a block of its own
    lone = build(cfg, "warehouse").model
    assert [lone.numeric(i).name for i in numeric_ids(lone)] == ["amr_tyres"]
    assert lone.body("amr/base_link").id > 0
