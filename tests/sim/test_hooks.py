"""The loop's hooks and observables: what they hand over, and that consumers use them instead of
reaching in."""

from __future__ import annotations

import ast
from pathlib import Path

import numpy as np
import pytest

from amr_twin.model.config import load_config
from amr_twin.recording.recorder import RAD_S_TO_RPM
from amr_twin.sim.hooks import HOOKS
from amr_twin.assembly.twin import Twin, TwinOptions
from amr_twin.recording.recorder import attach_recorder, recorder_of

ROOT = Path(__file__).resolve().parents[2]
CONSUMERS = (
    "amr_twin/recording",
    "amr_twin/live",
    "amr_twin/ros1",
    "amr_twin/sim/fault_injector.py",
)
"""What runs downstream of the loop and must hold to its hooks (the navigation stack's node sits on
the bus)."""
PARTS = frozenset(
    {"firmware", "plant", "hall", "physics", "samplers", "link", "rolling", "collisions", "_grid"}
)
"""The twin's parts a consumer must not reach into (it has ``on_*`` hooks and ``observables``)."""
TAPS = frozenset({"add_tap", "remove_tap"})
"""Bus methods a consumer reaches through ``twin.on_message`` / ``twin.unhook`` instead."""


def _is_twin(node: ast.expr) -> bool:
    """A twin or a robot: ``twin``, ``robot``, ``x.twin``, ``x.robot``."""
    return (isinstance(node, ast.Name) and node.id in ("twin", "robot")) or (
        isinstance(node, ast.Attribute) and node.attr in ("twin", "robot")
    )


def reaches(source: str) -> list[str]:
    """The places (``line: expression``) where ``source`` reaches into a twin's parts (module
    notes)."""
    found = []
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Attribute) and _is_twin(node.value) and node.attr in PARTS:
            found.append(f"{node.lineno}: {ast.unparse(node)}")
        elif (
            isinstance(node, ast.Attribute) and node.attr in TAPS
        ):  # a bus' taps, whichever name it goes by
            found.append(f"{node.lineno}: {ast.unparse(node)}")
    return found


def _consumer_modules():
    for name in CONSUMERS:
        path = ROOT / name
        yield from ([path] if path.suffix == ".py" else sorted(path.rglob("*.py")))


def test_consumers_subscribe_to_hooks_instead_of_reaching_into_the_twin():
    offenders = {str(p.relative_to(ROOT)): reaches(p.read_text()) for p in _consumer_modules()}
    offenders = {k: v for k, v in offenders.items() if v}
    assert not offenders, (
        f"reach into the twin's parts instead of its hooks and observables: {offenders}"
    )


@pytest.mark.parametrize(
    "source",
    [
        "def f(twin):\n    return twin.physics.data\n",
        "class C:\n    def g(self):\n        return self.twin.firmware.pins\n",
        "def f(twin):\n    twin.samplers.append(print)\n",
        "def f(twin):\n    twin.bus.add_tap(print)\n",
        "def f(capture):\n    return capture.twin.plant.battery\n",
        "def f(twin):\n    return twin.robot.hall\n",
        "class C:\n    def close(self):\n        self.bus.remove_tap(self._tap)\n",
    ],
)
def test_the_walk_sees_a_reach(source):
    assert reaches(source)


def test_the_walk_lets_hooks_through():
    source = (
        "def f(twin):\n    twin.on_grid(print)\n    twin.on_message(print, topics=('odom',))\n"
        "    twin.observables.drive()\n    twin.bus.publish('cmd_vel', None)\n"
    )
    assert reaches(source) == []


def test_the_firmware_protocol_declares_what_the_loop_calls():
    from amr_twin.controllers.firmware_params import Firmware

    declared = set(Firmware.__annotations__) | {n for n in vars(Firmware) if not n.startswith("_")}
    used = set()
    for name in ("amr_twin/assembly/robot.py", "amr_twin/sim/actuation.py"):
        for node in ast.walk(ast.parse((ROOT / name).read_text())):
            if (
                isinstance(node, ast.Attribute)
                and isinstance(node.value, ast.Attribute)
                and node.value.attr == "firmware"
            ):
                used.add(node.attr)
    assert used and used <= declared, (
        f"the loop calls {sorted(used - declared)} not declared by Firmware"
    )
    assert {"connect", "start", "on_sc_edge", "on_wheel_command", "pins"} <= declared


# -- what the hooks hand over
# -------------------------------------------------------------------------
@pytest.fixture(scope="module")
def hooked():
    """A 1.2 s run with a subscriber on each hook, and the twin (its recorder subscribed first)."""
    twin = Twin(load_config(), TwinOptions(world="empty", sensors=("imu", "lidar")))
    attach_recorder(twin)
    seen = {name: [] for name in HOOKS}
    twin.on_grid(lambda t_us: seen["on_grid"].append((t_us, twin.observables.loop_sensors())))
    twin.on_grid_rows(lambda t_us, rows: seen["on_grid_rows"].extend(zip(t_us, rows)))
    twin.on_event(lambda t_us: seen["on_event"].append(t_us))
    twin.on_actuation(
        lambda t_us: seen["on_actuation"].append((t_us, list(twin.observables.drive())))
    )
    twin.on_message(
        lambda topic, msg, t_us: seen["on_message"].append((topic, t_us)), topics=("odom",)
    )
    twin.client.linear(0.5)
    twin.advance(0.6)
    twin.client.stop()
    twin.advance(0.6)
    return twin, seen


def test_grid_hooks_see_every_record_instant_with_the_recorder_rows(hooked):
    twin, seen = hooked
    series = recorder_of(twin).series()
    grid = seen["on_grid"]
    assert [t for t, _ in grid] == list(range(10_000, 1_200_001, 10_000))
    assert [t for t, _ in seen["on_grid_rows"]] == [t for t, _ in grid]
    rows = np.array([r for _, r in seen["on_grid_rows"]])
    assert np.array_equal(
        rows, np.array([r for _, r in grid])
    )  # the observable at the instant = the row
    assert np.array_equal(rows[:, 2:4] * RAD_S_TO_RPM, series.true_rpm[1:])
    assert rows[-1, 4] > 0.2  # the robot drove forward (x, m)


def test_actuation_hook_fires_when_the_drive_changes_and_matches_the_recorder(hooked):
    twin, seen = hooked
    acts = seen["on_actuation"]
    pwm = [row[0] for _, row in acts]
    assert max(pwm) > 0 and pwm[-1] == 0  # drove, then stopped
    series = recorder_of(twin).series()
    act_t = np.array([t for t, _ in acts])
    for i, t_s in enumerate(
        series.t_s
    ):  # the recorder pairs each grid row with the drive in force then
        k = np.searchsorted(act_t, round(t_s * 1e6), side="left") - 1
        if (
            k < 0
        ):  # before the first actuation after hooking (the twin's start is the recorder's alone)
            continue
        row = acts[k][1]
        assert list(series.pwm_counts[i]) == row[0:2] and list(series.voltage_v[i]) == row[6:8]


def test_event_and_message_hooks(hooked):
    _, seen = hooked
    events = seen["on_event"]
    assert events == sorted(events)
    # the synced instants: the firmware's 0.2 s timer, the divergence checks (0.5 s), the command's
    # frame
    assert {200_000, 400_000, 500_000, 600_000, 800_000, 1_000_000, 1_200_000} <= set(events)
    assert 0 < events[0] < 200_000
    odom = seen["on_message"]
    assert odom and {topic for topic, _ in odom} == {"odom"}  # only the topics asked for
    assert [t for _, t in odom] == sorted(t for _, t in odom)


def test_unhook_removes_a_subscriber_from_its_hook():
    twin = Twin(load_config(), TwinOptions(world="empty", nodes=()))
    calls = []
    grid = twin.on_grid(lambda t_us: calls.append(("grid", t_us)))
    tap = twin.on_message(lambda topic, msg, t_us: calls.append((topic, t_us)))
    twin.advance(0.05)
    n = len(calls)
    assert n > 0
    twin.unhook(grid)
    twin.unhook(tap)
    twin.advance(0.05)
    assert len(calls) == n
    with pytest.raises(ValueError, match="hooked to nothing"):
        twin.unhook(grid)


def test_the_architecture_document_names_every_hook():
    doc = (ROOT / "docs" / "explanation" / "architecture.md").read_text()
    missing = [name for name in HOOKS if f"`{name}(" not in doc]
    assert not missing, f"docs/explanation/architecture.md does not describe {missing}"
    from amr_twin.sim.hooks import Hooks

    defined = {n for n in vars(Hooks) if n.startswith("on_")}
    assert defined == set(HOOKS), "HOOKS lists every on_* method of Hooks"


def test_collision_hook_tells_of_each_collision_once_at_its_first_contact():
    from amr_twin.model.worlds import Obstacle

    box = Obstacle("crate", 1.2, 0.0, (0.3, 1.0, 0.5))
    twin = Twin(
        load_config(), TwinOptions(world="empty", nodes=(), visuals=False, obstacles=(box,))
    )
    told = []
    twin.on_collision(lambda c: told.append((c.t_s, c.hit)))
    twin.client.linear(0.5)
    twin.advance(4.0)
    assert [hit for _, hit in told] == ["obstacle_crate"]  # one episode, told once
    ((t_s, _),) = told
    assert t_s == twin.observables.collisions[0].t_s and 1.0 < t_s < 3.5
    assert round(t_s * 1e6) % twin.grid_us == 0  # at a grid instant, in the sampler
