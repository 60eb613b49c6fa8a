"""A robot's parts: a component registered from a test module, listed in the options by name, gets
the loop's hooks, clock and bus; an unknown name is refused before any work."""

import pytest

from amr_twin import Twin, TwinOptions, load_config
from amr_twin.assembly.nodes import NODES
from amr_twin.ros.messages import Float64
from amr_twin.sim.component import Mount


class ActuationCounter:
    """A node of this module: counts the grid instants and the actuations it was told of, and
    publishes the count of grid instants every 100 ms."""

    def __init__(self, mount: Mount):
        self.grid, self.actuations = [], []
        mount.hooks.on_grid(self.grid.append)
        mount.hooks.on_actuation(self.actuations.append)
        self.published = []
        mount.bus.subscribe("grid_count", lambda msg: self.published.append(msg.data))
        self.pub = mount.bus.advertise("grid_count", Float64)
        mount.clock.schedule_every(100_000, 100_000, self._tick)

    def _tick(self) -> None:
        self.pub.publish(Float64(data=float(len(self.grid))))


@pytest.fixture
def registered():
    NODES.register("actuation_counter", lambda mount, cfg: ActuationCounter(mount))
    yield
    NODES.unregister("actuation_counter")


def test_a_node_listed_by_name_gets_the_hooks_clock_and_bus(registered):
    options = TwinOptions(world="empty", visuals=False, nodes=("odometry", "actuation_counter"))
    twin = Twin(load_config(), options)
    node = twin.nodes["actuation_counter"]
    assert list(twin.nodes) == ["odometry", "actuation_counter"]
    twin.client.linear(0.5)
    twin.advance(0.5)
    assert node.grid == list(range(0, 500_001, 10_000))  # at the start, then every grid instant
    assert node.actuations == [0, 5_000, 500_000]  # the start, the command's pins, the check
    assert node.published == [11.0, 21.0, 31.0, 41.0, 51.0]  # t = 0 and the instants up to now
    assert twin.robot.nodes is twin.nodes


def test_without_nodes_the_robot_has_none():
    twin = Twin(load_config(), TwinOptions(world="empty", visuals=False, nodes=()))
    assert twin.nodes == {}
    twin.reset_simulation()  # no odometry node to reset: still a reset


def test_an_unknown_node_is_refused_in_one_line_naming_the_choices():
    with pytest.raises(ValueError, match=r"^nodes 'sonar': must be one of odometry$"):
        Twin(load_config(), TwinOptions(world="empty", nodes=("sonar",)))


def test_nodes_are_a_tuple_of_names():
    with pytest.raises(ValueError, match=r"^nodes: 'odometry' must be a tuple of node names"):
        TwinOptions(nodes="odometry")
