"""Which bodies are whose robot, and a robot's own geoms hidden from its rays."""

import mujoco
import numpy as np

from amr_twin.model.build import build
from amr_twin.model.config import load_config
from amr_twin.model.robot_spec import GROUP_VISUAL
from amr_twin.model.robot_starts import fleet_starts
from amr_twin.sim.robot_bodies import (
    HIDDEN_GROUP,
    OwnGeoms,
    robot_indices,
    robot_name,
    robot_roots,
)

CFG = load_config()


def test_the_robots_of_a_world_are_found_and_named():
    m = build(CFG, "warehouse", robots=fleet_starts([(-4, 0, 0), (-2, 0, 0), (-4, 2, 0)])).model
    roots = np.flatnonzero(robot_roots(m))
    assert [robot_name(m, r) for r in roots] == ["amr-1", "amr-2", "amr-3"]
    lone = build(CFG, "warehouse").model
    assert [robot_name(lone, r) for r in np.flatnonzero(robot_roots(lone))] == ["amr"]


def test_own_geoms_are_hidden_inside_the_block_only_and_a_lone_robot_changes_nothing():
    m = build(CFG, "warehouse", robots=fleet_starts([(-4, 0, 0), (-2, 0, 0)])).model
    one, two = (m.body(f"amr-{i}/base_link").id for i in (1, 2))
    own = OwnGeoms(m, m.body("amr-1/laser").id)
    before = m.geom_group.copy()
    mine = m.body_rootid[m.geom_bodyid] == one
    with own:
        assert (m.geom_group[mine & (before == GROUP_VISUAL)] == HIDDEN_GROUP).all()
        assert (m.geom_group[~mine] == before[~mine]).all()  # robot 2's stay seen
    assert (m.geom_group == before).all() and own.others
    assert own.seeing_others(np.array([1, 0, 0, 0, 1, 0], np.uint8)).tolist() == [1, 1, 0, 0, 1, 0]
    assert (m.body_rootid[m.geom_bodyid] == two).any()
    lone = build(CFG, "warehouse").model
    alone = OwnGeoms(lone, lone.body("amr/laser").id)
    groups = lone.geom_group.copy()
    with alone:
        assert (lone.geom_group == groups).all()
    assert not alone.others
    assert alone.seeing_others(np.array([1, 0, 0, 0, 1, 0], np.uint8)).tolist() == [
        1,
        0,
        0,
        0,
        1,
        0,
    ]
    assert mujoco.mjNGROUP > HIDDEN_GROUP


def test_each_robots_joints_are_its_own_slice_of_the_state():
    m = build(CFG, "warehouse", robots=fleet_starts([(-4, 0, 0), (-2, 0, 0)])).model
    (q1, v1), (q2, v2) = (robot_indices(m, m.body(f"amr-{i}/base_link").id) for i in (1, 2))
    assert q1.tolist() == list(range(15)) and q2.tolist() == list(range(15, 30)) and m.nq == 30
    assert v1.tolist() == list(range(14)) and v2.tolist() == list(range(14, 28)) and m.nv == 28
    lone = build(CFG, "warehouse").model
    q, v = robot_indices(lone, lone.body("amr/wheel_left_link").id)
    assert q.tolist() == list(range(lone.nq)) and v.tolist() == list(range(lone.nv))
