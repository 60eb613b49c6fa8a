"""Mission files: a timed list of wheel_Command_Client calls, run in one go.

Reasons and measurements: docs/explanation/architecture.md#amr_twinassemblymission."""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

from amr_twin.sim.bounds import duration_problem
from amr_twin.assembly.command import KINDS, Command
from amr_twin.model.yaml_file import read_yaml

FIELDS = {
    "linear": {"speed_m_s": True},
    "angular": {"speed_deg_s": True, "icc_m": False},
    "motor": {"wheel": True, "direction": True, "speed_m_s": True},
    "stop": {},
}
"""Per command kind: its fields and whether each is required."""


class MissionError(ValueError):
    """A mission file is invalid; the message is one line."""


def _number(where: str, value) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise MissionError(f"{where}: {value!r} is not a number")
    if not math.isfinite(value):
        raise MissionError(f"{where}: {value} must be a finite number")
    return float(value)


def parse_step(index: int, step) -> tuple[float, Command]:
    """One step ``{t_s: ..., <kind>: {...}}`` to ``(t_s, Command)``."""
    where = f"steps[{index}]"
    if not isinstance(step, dict):
        raise MissionError(f"{where}: expected a mapping with t_s and one of {', '.join(KINDS)}")
    if "t_s" not in step:
        raise MissionError(f"{where}: t_s is missing")
    t_s = _number(f"{where}.t_s", step["t_s"])
    kinds = [k for k in step if k != "t_s"]
    unknown = [k for k in kinds if k not in FIELDS]
    if unknown:
        raise MissionError(
            f"{where}: unknown key {unknown[0]!r} (expected t_s and one of {', '.join(KINDS)})"
        )
    if len(kinds) != 1:
        raise MissionError(f"{where}: needs exactly one of {', '.join(KINDS)}, got {len(kinds)}")
    kind = kinds[0]
    args = step[kind] if step[kind] is not None else {}
    if not isinstance(args, dict):
        raise MissionError(
            f"{where}.{kind}: expected a mapping of {', '.join(FIELDS[kind]) or 'nothing'}"
        )
    for name in args:
        if name not in FIELDS[kind]:
            raise MissionError(
                f"{where}.{kind}: unknown field {name!r} "
                f"(expected {', '.join(FIELDS[kind]) or 'none'})"
            )
    values = {}
    for name, required in FIELDS[kind].items():
        if name not in args:
            if required:
                raise MissionError(f"{where}.{kind}.{name} is missing")
            continue
        if name in ("wheel", "direction"):
            values[name] = str(args[name])
        else:
            values[name] = _number(f"{where}.{kind}.{name}", args[name])
    try:
        return t_s, Command(kind, **values)
    except ValueError as exc:
        raise MissionError(f"{where}.{kind}: {exc}") from None


@dataclass(frozen=True)
class Mission:
    """A validated mission: its length, its timed commands and its fault specifications; or its
    goals ``(x_m, y_m, yaw_rad or None)`` with the navigation's ``map``, ``localisation`` and
    ``controller``."""

    duration_s: float | None
    steps: list[tuple[float, Command]]
    faults: tuple[str, ...] = ()
    actors: tuple = ()  # amr_twin.model.actors.Actor items
    goals: tuple = ()
    navigation: dict | None = None


NAV_KEYS = ("map", "localisation", "controller")


def parse_goal(where: str, goal) -> tuple[float, float, float | None]:
    """``[x_m, y_m]``, ``[x_m, y_m, yaw_deg]`` or ``{x_m, y_m, yaw_deg}`` to ``(x_m, y_m, yaw_rad or
    None)``."""
    if isinstance(goal, dict):
        unknown = [k for k in goal if k not in ("x_m", "y_m", "yaw_deg")]
        if unknown or "x_m" not in goal or "y_m" not in goal:
            raise MissionError(f"{where}: expected x_m, y_m and optionally yaw_deg")
        values = [goal["x_m"], goal["y_m"]] + ([goal["yaw_deg"]] if "yaw_deg" in goal else [])
    elif isinstance(goal, list) and len(goal) in (2, 3):
        values = goal
    else:
        raise MissionError(
            f"{where}: expected [x_m, y_m], [x_m, y_m, yaw_deg] or a mapping of them"
        )
    numbers = [_number(f"{where}[{i}]", v) for i, v in enumerate(values)]
    if any(abs(v) > 1e4 for v in numbers):
        raise MissionError(f"{where}: each value must lie within +-10000")
    return numbers[0], numbers[1], math.radians(numbers[2]) if len(numbers) == 3 else None


def _goals_plan(tree: dict) -> Mission:
    goals = tree["goals"]
    if "steps" in tree:
        raise MissionError("mission: give steps (wheel commands) or goals (navigation), not both")
    if not isinstance(goals, list) or not goals:
        raise MissionError("goals: must be a non-empty list of [x_m, y_m] or [x_m, y_m, yaw_deg]")
    duration_s = None
    if "duration_s" in tree:
        duration_s = _number("duration_s", tree["duration_s"])
        if duration_s <= 0:
            raise MissionError(f"duration_s: {duration_s} must be > 0")
    nav = {}
    for key in NAV_KEYS:
        if key in tree:
            if not isinstance(tree[key], str) or not tree[key]:
                raise MissionError(f"{key}: {tree[key]!r} must be a name or a file path")
            nav[key] = tree[key]
    return Mission(
        duration_s,
        [],
        _faults(tree),
        _actors(tree),
        tuple(parse_goal(f"goals[{i}]", g) for i, g in enumerate(goals)),
        nav,
    )


def parse_mission(tree) -> tuple[float, list[tuple[float, Command]]]:
    """A loaded mission mapping to ``(duration_s, [(t_s, Command), ...])`` (see
    :func:`parse_mission_plan`)."""
    plan = parse_mission_plan(tree)
    return plan.duration_s, plan.steps


def _faults(tree) -> tuple[str, ...]:
    from amr_twin.sim.faults import FaultError, parse_faults

    faults = tree.get("faults") or []
    if not isinstance(faults, list) or not all(isinstance(f, str) for f in faults):
        raise MissionError(
            "faults: expected a list of KIND@T[:ARGS] strings, e.g. [hall-left-dead@3]"
        )
    try:
        parse_faults(
            faults, where="faults"
        )  # the run checks them again against its duration and sensors
    except FaultError as exc:
        raise MissionError(str(exc)) from None
    return tuple(faults)


def _actors(tree) -> tuple:
    from amr_twin.model.actors import Actor, ActorError

    actors = tree.get("actors") or []
    if not isinstance(actors, list):
        raise MissionError(
            "actors: expected a list of {kind, waypoints_xy_m, speed_m_s, ...} mappings"
        )
    try:
        return tuple(Actor.from_mapping(a, f"actors[{i}]") for i, a in enumerate(actors))
    except ActorError as exc:
        raise MissionError(str(exc)) from None


def parse_mission_plan(tree) -> Mission:
    """A loaded mission mapping to a :class:`Mission`."""
    if not isinstance(tree, dict):
        raise MissionError("mission: expected a mapping with duration_s and steps (or goals)")
    unknown = [
        k for k in tree if k not in ("duration_s", "steps", "faults", "actors", "goals") + NAV_KEYS
    ]
    if unknown:
        raise MissionError(
            f"mission: unknown key {unknown[0]!r} (expected duration_s, steps, faults, actors; "
            f"or goals, {', '.join(NAV_KEYS)})"
        )
    if "goals" in tree:
        return _goals_plan(tree)
    extra = [k for k in NAV_KEYS if k in tree]
    if extra:
        raise MissionError(f"{extra[0]}: a navigation key, given without goals")
    if "duration_s" not in tree:
        raise MissionError("mission: duration_s is missing")
    duration_s = _number("duration_s", tree["duration_s"])
    if duration_problem(duration_s):
        raise MissionError(f"duration_s: {duration_s:g} {duration_problem(duration_s)}")
    steps = tree.get("steps")
    if not isinstance(steps, list) or not steps:
        raise MissionError("mission: steps must be a non-empty list")
    parsed = [parse_step(i, s) for i, s in enumerate(steps)]
    for i, (t_s, _) in enumerate(parsed):
        if not 0.0 <= t_s <= duration_s:
            raise MissionError(f"steps[{i}].t_s: {t_s} must lie in [0, {duration_s}] s")
    return Mission(duration_s, sorted(parsed, key=lambda s: s[0]), _faults(tree), _actors(tree))


def load_mission_file(path: str | Path) -> Mission:
    """Read and validate a mission YAML file."""
    path = Path(path)
    tree = read_yaml(path, "mission", MissionError)
    try:
        plan = parse_mission_plan(tree)
    except MissionError as exc:
        raise MissionError(f"mission {path}: {exc}") from None
    if (
        plan.navigation
        and "map" in plan.navigation
        and not Path(plan.navigation["map"]).is_absolute()
    ):
        plan.navigation["map"] = str(
            path.parent / plan.navigation["map"]
        )  # beside the mission file
    return plan
