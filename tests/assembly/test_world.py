"""A world and its robots: a World built by hand with one robot runs as the Twin does, to the bit;
the robots' hall edges reach their firmwares in time order."""

import numpy as np
import pytest

from amr_twin.assembly.robot import RobotSpec
from amr_twin.assembly.twin import Twin, TwinOptions
from amr_twin.assembly.world import World, deliver_in_time_order
from amr_twin.base.clock import VirtualClock
from amr_twin.model.config import load_config
from amr_twin.sim.settled_physics import settled_physics

START = (0.0, 0.0, 0.0)


def _drive(world, robot) -> list:
    """Rows of every grid instant through a turn, a straight and a stop."""
    rows = []
    world.on_grid_rows(lambda t_us, chunk: rows.extend(zip(t_us, chunk)))
    robot.client.angular(45.0, 0.5)
    world.advance(1.0)
    robot.client.linear(0.6)
    world.advance(1.0)
    robot.client.stop()
    world.advance(0.5)
    return rows


@pytest.mark.parametrize("firmware", ["faithful", "improved"])
def test_a_world_with_one_robot_drives_as_the_twin_to_the_bit(firmware):
    cfg = load_config()
    twin = Twin(cfg, TwinOptions(world="empty", firmware=firmware, visuals=False))
    by_twin = _drive(twin, twin)
    physics, _ = settled_physics(cfg, "empty", START, False, False, 0.5, "test", (), ())
    world = World(
        physics,
        [RobotSpec(cfg, START, world="empty", firmware=firmware)],
        grid_every=10,
        check_every_s=0.5,
    )
    (robot,) = world.robots
    by_world = _drive(world, robot)
    assert [t for t, _ in by_world] == list(range(10_000, 2_500_001, 10_000))
    assert [t for t, _ in by_world] == [t for t, _ in by_twin]
    np.testing.assert_array_equal([r for _, r in by_world], [r for _, r in by_twin])
    assert abs(by_world[-1][1][4]) > 0.3  # the robot moved (x, m): not two resting runs
    assert robot.observables.drive() == twin.observables.drive()


class _Firmware:
    def __init__(self, clock, log, name):
        self.clock, self.log, self.name = clock, log, name

    def on_sc_edge(self, wheel: int) -> None:
        self.log.append((self.clock.now_us, self.name, wheel))


class _Robot:
    def __init__(self, clock, log, name, pending):
        self.firmware, self.pending = _Firmware(clock, log, name), list(pending)


def test_two_robots_edges_reach_their_firmwares_in_time_order_each_at_its_time():
    clock, log = VirtualClock(), []
    a = _Robot(clock, log, "a", [(100, 0), (300, 1), (900, 0)])
    b = _Robot(clock, log, "b", [(100, 1), (200, 0), (500, 1)])
    deliver_in_time_order(clock, [a, b], 500)
    assert log == [(100, "a", 0), (100, "b", 1), (200, "b", 0), (300, "a", 1), (500, "b", 1)]
    assert a.pending == [(900, 0)] and b.pending == []  # the later edge waits for its instant
