"""A world of several robots: each robot moves by its own firmware's commands only, robots that
meet collide and the record names both, bad input is refused before the build."""

import math

import pytest

from amr_twin.assembly.fleet_world import fleet_world
from amr_twin.assembly.twin import TwinOptions
from amr_twin.model.config import load_config
from amr_twin.controllers.wheel_command import BACKWARD, FORWARD

CFG = load_config()
OPTIONS = TwinOptions(world="empty", firmware="improved", visuals=False)


def _pose(robot) -> tuple[float, float, float]:
    row = robot.observables.loop_sensors()
    w, x, y, z = row[7:11]
    return row[4], row[5], math.atan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z))


def test_each_robot_moves_by_the_command_on_its_own_bus_only():
    world = fleet_world(CFG, OPTIONS, [(0.0, 0.0, 0.0), (0.0, 3.0, 0.0)])
    a, b = world.robots
    assert (a.name, b.name) == ("amr-1", "amr-2") and a.bus is not b.bus
    assert len(a.observables.loop_sensors()) == len(b.observables.loop_sensors()) == 11
    a.service.send_command(FORWARD, 60.0, FORWARD, 60.0)  # wheel_Command on a's bus: ahead
    b.service.send_command(BACKWARD, 30.0, FORWARD, 30.0)  # on b's: a turn in place
    world.advance(2.0)
    (ax, ay, ayaw), (bx, by, byaw) = _pose(a), _pose(b)
    assert ax > 0.5 and abs(ay) < 0.05 and abs(ayaw) < 0.1  # a drove ahead
    assert math.hypot(bx, by - 3.0) < 0.05 and abs(byaw) > 0.5  # b turned where it stood
    assert world.collision_records() == []
    with pytest.raises(
        ValueError, match="on_message: a fleet's robots speak on buses of their own"
    ):
        world.on_message(lambda *_: None)  # a recorder on the world's bus would hear nothing


def test_two_robots_driven_head_on_collide_and_the_record_names_both():
    world = fleet_world(CFG, OPTIONS, [(-1.0, 0.0, 0.0), (1.0, 0.0, math.pi)])
    for robot in world.robots:
        robot.client.linear(0.4)
    world.advance(4.0)
    records = world.collision_records()
    assert {(r["robot"], r["hit"]) for r in records} == {("amr-1", "amr-2"), ("amr-2", "amr-1")}
    (ax, _, _), (bx, _, _) = (_pose(r) for r in world.robots)
    assert -0.8 < ax < bx < 0.8  # they met in the middle, neither passed through


@pytest.mark.parametrize(
    "poses, message",
    [
        ([(0.0, 0.0, 0.0)], "robots: 1 start poses"),
        ([(0.0, 0.0, 0.0)] * 21, "robots: 21 start poses; 1 to 20"),
        ([(0.0, 0.0, 0.0), (0.2, 0.0, 0.0)], "amr-1 start 0,0,0"),
    ],
)
def test_bad_fleets_are_refused_in_one_line(poses, message):
    with pytest.raises(ValueError, match=message) as info:
        fleet_world(CFG, OPTIONS, poses)
    assert "\n" not in str(info.value)
