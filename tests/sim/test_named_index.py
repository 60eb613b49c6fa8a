"""Named views of MjModel and MjData (``physics.named``), checked against MuJoCo's own accessors."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from amr_twin.model.build import build
from amr_twin.model.config import load_config
from amr_twin.sim.physics import Physics
from amr_twin.sim.named_index import NamedIndex


@pytest.fixture(scope="module")
def physics():
    p = Physics(build(load_config(), world="empty").model)
    p.step(50)  # something moving: the wheels and the base away from their start values
    return p


def test_names_select_the_rows_mujoco_gives_for_them(physics):
    named, d = physics.named, physics.data
    assert named.data.qpos["amr/wheel_left_joint"] == d.joint("amr/wheel_left_joint").qpos[0]
    assert np.array_equal(
        named.data.qpos["amr/root"], d.joint("amr/root").qpos
    )  # free joint: 7 values
    assert np.array_equal(named.data.qvel["amr/root"], d.joint("amr/root").qvel)  # 6 dofs
    assert np.array_equal(named.data.xpos["amr/base_link"], d.body("amr/base_link").xpos)
    assert np.array_equal(named.data.sensordata["amr/imu_gyro"], d.sensor("amr/imu_gyro").data)
    assert np.array_equal(
        named.data.geom_xpos["amr/wheel_right_collision"], d.geom("amr/wheel_right_collision").xpos
    )
    assert named.model.body_mass["amr/base_link"] == physics.model.body("amr/base_link").mass[0]
    both = named.data.qpos[["amr/wheel_left_joint", "amr/wheel_right_joint"]]
    assert np.array_equal(both, physics.wheel_angles_rad())  # left, right in that order


def test_a_write_through_a_named_view_reaches_mjdata():
    p = Physics(build(load_config(), world="empty").model)
    p.named.data.qvel["amr/wheel_right_joint"] = 2.5
    assert p.data.joint("amr/wheel_right_joint").qvel[0] == 2.5
    assert p.wheel_speeds_list()[1] == 2.5


def test_an_unknown_name_says_which_field_and_kind(physics):
    with pytest.raises(KeyError, match="xpos: the model has no body named 'amr/nowhere'"):
        physics.named.data.xpos["amr/nowhere"]
    with pytest.raises(KeyError, match="sensordata: the model has no sensor"):
        physics.named.data.sensordata["amr/wheel_left_joint"]


def test_positional_keys_index_the_array_as_it_is(physics):
    assert np.array_equal(physics.named.data.xpos[1:3], physics.data.xpos[1:3])
    assert physics.named.data.qpos[0] == physics.data.qpos[0]


@pytest.mark.parametrize("native", [True, False])
def test_value_rows_keep_the_named_values_at_each_grid_instant(physics, native):
    d = physics.named.data
    rows = NamedIndex.value_rows(
        [(d.qpos, ["amr/wheel_left_joint", "amr/wheel_right_joint"]), (d.xpos, ["amr/base_link"])],
        native=native,
    )
    kept = []
    for t_us in (1000, 2000, 3000):
        physics.step(1)
        rows(t_us)
        kept.append([*physics.wheel_angles_rad(), *physics.data.body("amr/base_link").xpos])
    table = rows.rows
    assert np.array_equal(table[:, 0], [1000, 2000, 3000])
    assert np.array_equal(table[:, 1:], np.array(kept))


def test_a_clone_has_named_views_of_its_own_data(physics):
    twin = physics.clone()
    twin.step(20)
    assert not np.array_equal(twin.named.data.qpos["amr/root"], physics.named.data.qpos["amr/root"])
    assert np.array_equal(twin.named.data.qpos["amr/root"], twin.data.qpos[:7])
    assert mujoco.mj_name2id(twin.model, mujoco.mjtObj.mjOBJ_BODY, "amr/base_link") >= 0
