"""One robot of a fleet seen as a lone twin: its own bus, its own columns of the grid rows."""

from amr_twin.assembly.fleet_world import fleet_world
from amr_twin.assembly.robot_view import RobotView
from amr_twin.assembly.twin import TwinOptions
from amr_twin.controllers.wheel_command import FORWARD
from amr_twin.model.config import load_config


def test_the_view_hands_over_the_robots_own_rows_and_messages():
    world = fleet_world(
        load_config(),
        TwinOptions(world="empty", firmware="improved", visuals=False),
        [(0.0, 0.0, 0.0), (0.0, 3.0, 0.0)],
    )
    a, b = world.robots
    view = RobotView(world, b, "amr-2")
    rows, heard = [], []
    view.on_grid_rows(lambda t_us, r: rows.extend(r))
    tap = view.on_message(lambda topic, msg, t_us: heard.append(topic), topics=("odom",))
    a.service.send_command(FORWARD, 60.0, FORWARD, 60.0)  # only robot 1 drives
    world.advance(1.0)
    assert rows and list(rows[-1]) == list(b.observables.loop_sensors())
    assert abs(rows[-1][5] - 3.0) < 0.01  # robot 2's y, not robot 1's
    assert heard and view.start_xy_yaw == (0.0, 3.0, 0.0) and view.prefix == "amr-2/"
    view.unhook(tap)
    n = len(heard)
    world.advance(0.2)
    assert len(heard) == n
