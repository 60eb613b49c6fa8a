"""The run's own commands yield to move_base's goals (amr_twin/ros1/navigation_setup.py), without a
graph: the stack attached to a run's twin as ``run ... --sensors --ros1`` attaches it, a goal sent
to its navigator as the action server sends it, and the run's next command (a mission's step) due
while the goal is active."""

import math

import pytest

from amr_twin.controllers.diff_drive import DiffDriveNode
from amr_twin.model.config import load_config
from amr_twin.navigation.stack import true_map
from amr_twin.ros1.navigation_setup import RunNavigation
from amr_twin.assembly.twin import Twin, TwinOptions
from amr_twin.assembly.command import Command
from amr_twin.recording.recorder import attach_recorder, recorder_of

START = (-6.0, 0.0, 0.0)
GOAL = (-3.0, 0.0, 0.0)


@pytest.fixture(scope="module")
def run():
    cfg = load_config()
    twin = Twin(
        cfg,
        TwinOptions(
            firmware="improved", sensors=("imu", "lidar"), world="warehouse", start_xy_yaw=START
        ),
    )
    attach_recorder(twin)
    navigation = RunNavigation(cfg, true_map(cfg, "warehouse"))
    nav = navigation.attach(twin)
    DiffDriveNode(twin.bus, twin.clock, twin.client)  # the run's cmd_vel node (amr_twin/cli/run.py)
    lines = []
    ((_t, step),) = navigation.yielding([(3.0, Command("linear", speed_m_s=0.5))], say=lines.append)
    outcome = nav.send_goal(GOAL)
    twin.advance(3.0)
    during = step.send(twin), twin.client.last_request
    while outcome.status == "pending" and twin.t_s < 40.0:
        twin.advance(0.5)
    twin.advance(2.0)
    after_goal = recorder_of(twin).series().pose[-1]
    code = step.send(twin)
    return (
        outcome,
        during,
        after_goal,
        code,
        twin.client.last_request,
        lines,
        _fields(step.command.dry_run(cfg).last_request),
    )


def _fields(request) -> tuple:
    return (
        None
        if request is None
        else (request.motionL, request.speedL, request.motionR, request.speedR)
    )


def test_a_command_due_while_a_goal_is_active_is_not_sent_and_the_goal_is_reached(run):
    outcome, (code, request), after_goal, _code, _request, lines, linear = run
    assert code == 0 and len(lines) == 1 and "linear command at t = 3.00 s not sent" in lines[0]
    assert _fields(request) != linear  # the navigator's last command stands
    assert outcome.status == "succeeded", outcome.reason
    assert math.hypot(after_goal[0] - GOAL[0], after_goal[1] - GOAL[1]) < 0.3


def test_a_command_after_the_goal_is_sent(run):
    _outcome, _during, _after, code, request, lines, linear = run
    assert code == 0 and len(lines) == 1
    assert _fields(request) == linear and linear[1] > 0  # 0.5 m/s forward, as the run asked
