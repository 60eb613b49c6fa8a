"""One door to MuJoCo's state: outside the physics layer no module touches MjData.

The physics layer is :mod:`amr_twin.sim.physics` and every module that declares
``PHYSICS_LAYER = True`` (with its reason in the module notes). Everywhere else, in the
packages amr_twin, sensors, controllers and experiments, a module's syntax tree must not:

- name ``mujoco.MjData`` (make or annotate an MjData);
- call a ``mujoco.mj_*`` function other than the model-only ones (names and ids);
- take ``.data`` of a physics (``physics.data``, ``self.physics.data``, ``twin.physics.data``);
- take a data's ``._address`` (hand MjData to C).

Read MuJoCo's state through :class:`~amr_twin.sim.physics.Physics` (its methods and its named
views, ``physics.named.data``) or the twin's observables.
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
PACKAGES = ("amr_twin", "sensors", "controllers", "experiments")
MODEL_ONLY = frozenset({"mj_name2id", "mj_id2name", "mj_versionString", "mj_version"})
"""``mujoco.mj_*`` functions that read the model alone."""


def _physics_layer(tree: ast.Module) -> bool:
    for node in tree.body:
        if isinstance(node, ast.Assign) and any(
            isinstance(t, ast.Name) and t.id == "PHYSICS_LAYER" for t in node.targets
        ):
            return isinstance(node.value, ast.Constant) and node.value.value is True
    return False


def _ends_with_physics(node: ast.expr) -> bool:
    name = (
        node.attr
        if isinstance(node, ast.Attribute)
        else node.id
        if isinstance(node, ast.Name)
        else ""
    )
    return "physics" in name


def touches(source: str) -> list[str]:
    """The places (``line: what``) where ``source`` touches MjData outside the physics layer (module
    notes)."""
    tree = ast.parse(source)
    if _physics_layer(tree):
        return []
    found = []
    for node in ast.walk(tree):
        if not isinstance(node, ast.Attribute):
            continue
        base = node.value
        if isinstance(base, ast.Name) and base.id == "mujoco":
            if node.attr == "MjData":
                found.append(f"{node.lineno}: mujoco.MjData")
            elif node.attr.startswith("mj_") and node.attr not in MODEL_ONLY:
                found.append(f"{node.lineno}: mujoco.{node.attr}")
        elif node.attr == "data" and _ends_with_physics(base):
            found.append(f"{node.lineno}: {ast.unparse(node)}")
        elif node.attr == "_address":
            found.append(f"{node.lineno}: {ast.unparse(node)}")
    return found


def _modules():
    for package in PACKAGES:
        for path in sorted((ROOT / package).rglob("*.py")):
            yield path


def test_no_module_outside_the_physics_layer_touches_mjdata():
    offenders = {}
    for path in _modules():
        places = touches(path.read_text())
        if places:
            offenders[str(path.relative_to(ROOT))] = places
    assert not offenders, (
        "touch MjData outside the physics layer (go through Physics or the twin's observables, "
        f"or declare PHYSICS_LAYER = True with the reason): {offenders}"
    )


def test_the_physics_layer_says_why():
    """A module of the physics layer says so in its notes, with the reason."""
    silent = []
    for path in _modules():
        source = path.read_text()
        tree = ast.parse(source)
        if _physics_layer(tree) and path.name != "physics.py":
            doc = ast.get_docstring(tree) or ""
            if "physics layer" not in doc.lower():
                silent.append(str(path.relative_to(ROOT)))
    assert not silent, f"PHYSICS_LAYER without a word on why in the module notes: {silent}"


@pytest.mark.parametrize(
    "source, what",
    [
        ("import mujoco\nd = mujoco.MjData(m)\n", "mujoco.MjData"),
        ("import mujoco\nmujoco.mj_step(m, d)\n", "mujoco.mj_step"),
        ("x = twin.physics.data.qpos[0]\n", "twin.physics.data"),
        ("def f(self):\n    return self.physics.data.xpos\n", "self.physics.data"),
        ("p = data._address\n", "data._address"),
    ],
)
def test_the_walk_sees_each_kind_of_touch(source, what):
    assert any(what in place for place in touches(source))
    assert touches("PHYSICS_LAYER = True\n" + source) == []


def test_the_walk_lets_the_doors_through():
    source = (
        "import mujoco\ni = mujoco.mj_name2id(m, k, 'amr/base_link')\n"
        "q = physics.named.data.qpos['amr/root']\nrow = twin.observables.loop_sensors()\nmsg.data\n"
    )
    assert touches(source) == []
