"""The navigation's plug-in points: a local controller defined here, registered by name, drives."""

import math
import subprocess
import sys

import pytest

from amr_twin import (
    CONTROLLERS,
    LOCALISATIONS,
    LocalController,
    NavigationOptions,
    Twist2D,
    TwinOptions,
    load_config,
    navigate,
)
from amr_twin.navigation.registries import PLANNERS, RECOVERIES, ROUND_ROBIN

CFG = load_config()
TOP_M_S = 0.3
"""The plug-in's top speed, m/s: below the built-ins' 0.8, so the commands show whose they are."""


class StraightAtGoal(LocalController):
    """Turns to the plan's goal and drives straight at it: no costmap, no people (the defaults)."""

    calls = 0

    def command(self, pose, velocity, path, people, t_s):
        StraightAtGoal.calls += 1
        gx, gy = path.goal[:2]
        err = math.remainder(math.atan2(gy - pose[1], gx - pose[0]) - pose[2], 2 * math.pi)
        v = min(TOP_M_S, math.hypot(gx - pose[0], gy - pose[1])) if abs(err) < 0.5 else 0.0
        return Twist2D(v, max(-1.0, min(1.0, 2.0 * err)))


@pytest.fixture
def straight():
    CONTROLLERS.register("straight", lambda costmap, footprint, nav, seed: StraightAtGoal())
    StraightAtGoal.calls = 0
    yield "straight"
    CONTROLLERS.unregister("straight")


def _go(controller: str):
    twin = TwinOptions(
        firmware="improved", world="warehouse", start_xy_yaw=(-6.0, 0.0, 0.0), visuals=False, seed=0
    )
    return navigate(
        CFG,
        twin,
        NavigationOptions(
            goals=((-4.0, 0.5, None),), localisation="truth", controller=controller, timeout_s=30.0
        ),
    )


def test_a_controller_registered_by_a_test_module_drives_the_robot_to_the_goal(straight):
    run = _go(straight)
    assert run.outcomes[0].status == "succeeded", run.outcomes[0].reason
    x, y, _ = run.pose_true[-1]
    assert math.hypot(x + 4.0, y - 0.5) <= 0.25 and run.collisions == []
    assert StraightAtGoal.calls > 20  # it drove: every control cycle of the way went through it
    assert 0.2 < run.commands[:, 1].max() <= TOP_M_S + 1e-9  # its speed, not MPPI's 0.8 m/s


def test_an_unknown_plug_in_is_refused_in_one_line_naming_the_option_and_the_choices():
    with pytest.raises(ValueError) as exc:
        _go("straight")  # not registered outside the fixture
    assert str(exc.value) == "--controller 'straight': must be one of mppi or rpp"


def test_the_built_ins_are_listed_without_loading_their_modules():
    """The command line's help lists them at start-up: no numpy, no controller's module."""
    code = (
        "import sys; from amr_twin.navigation import registries as r; "
        "print([r.help_text(k) for k in (r.CONTROLLERS, r.LOCALISATIONS, r.PLANNERS, "
        "r.RECOVERIES)], sorted(m for m in ('numpy', 'amr_twin.navigation.mppi', "
        "'amr_twin.navigation.planner') if m in sys.modules))"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, timeout=60, check=True
    )
    assert out.stdout.strip().endswith("[]") and "rpp (regulated pure pursuit)" in out.stdout
    assert CONTROLLERS.names() == ("mppi", "rpp")
    assert LOCALISATIONS.names() == ("truth", "ekf", "odom")
    assert PLANNERS.names() == ("grid",) and RECOVERIES.names() == ROUND_ROBIN
