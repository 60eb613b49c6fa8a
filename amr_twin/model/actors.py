"""Things that move in a world: people and pallet jacks on scripted paths, as MuJoCo mocap bodies.

An :class:`Actor` walks its waypoints at a constant speed, heading along each segment, and
turns on the spot at each corner at its kind's turn rate (``actors.<kind>.turn_rate_rad_s``);
from ``start_s`` on, once (then it stands at its last waypoint) or in a ``loop`` (back to the
first). Its timing is :mod:`amr_twin.model.actor_paths`; the loop moves it
(:mod:`amr_twin.sim.actors`). Scripted actors do not avoid anything: with ``stop_within_m`` a
person (or a jack) halts while the robot's footprint is that close ahead of it, and walks on
when it is not.

Reasons and measurements: docs/explanation/actors.md#amr_twinmodelactors."""

from __future__ import annotations

import math
from dataclasses import dataclass

KINDS = ("person", "pallet_jack")
MAX_COORD_M = 1e4
MAX_START_S = 1e6
MAX_STOP_M = 10.0


class ActorError(ValueError):
    """An actor is invalid; the message is one line naming it and the field."""


def _finite(where: str, value, lo: float = -math.inf, hi: float = math.inf) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise ActorError(f"{where}: {value!r} is not a finite number")
    if not lo <= value <= hi:
        raise ActorError(f"{where}: {value:g} must lie in [{lo:g}, {hi:g}]")
    return float(value)


@dataclass(frozen=True)
class Actor:
    """A person or pallet jack on a scripted path (module notes).

    ``kind``: ``"person"`` or ``"pallet_jack"``; ``waypoints_xy_m``: world points (x, y), m,
    at least one (one: it stands there facing +x); ``speed_m_s``: along the segments;
    ``start_s``: when it sets off (it stands at its first waypoint before); ``loop``: back to the
    first waypoint and round again; ``stop_within_m``: halt while the robot's footprint is
    nearer than this ahead of it, m (0: never).
    """

    kind: str
    waypoints_xy_m: tuple[tuple[float, float], ...]
    speed_m_s: float
    start_s: float = 0.0
    loop: bool = False
    stop_within_m: float = 0.0

    def __post_init__(self) -> None:
        if self.kind not in KINDS:
            raise ActorError(f"actor kind {self.kind!r}: must be one of {', '.join(KINDS)}")
        try:
            points = tuple((float(x), float(y)) for x, y in self.waypoints_xy_m)
        except (TypeError, ValueError):
            raise ActorError(
                f"{self.kind}: waypoints_xy_m must be a list of (x, y) pairs in m"
            ) from None
        if not points:
            raise ActorError(f"{self.kind}: waypoints_xy_m needs at least one (x, y) point")
        for i, (x, y) in enumerate(points):
            _finite(f"{self.kind}: waypoint {i} x", x, -MAX_COORD_M, MAX_COORD_M)
            _finite(f"{self.kind}: waypoint {i} y", y, -MAX_COORD_M, MAX_COORD_M)
            if i and points[i - 1] == (x, y):
                raise ActorError(
                    f"{self.kind}: waypoints {i - 1} and {i} coincide at ({x:g}, {y:g})"
                )
        if self.loop and (len(points) < 2 or (len(points) == 2 and points[0] == points[1])):
            raise ActorError(f"{self.kind}: a loop needs at least two distinct waypoints")
        object.__setattr__(self, "waypoints_xy_m", points)
        _finite(f"{self.kind}: speed_m_s", self.speed_m_s, 1e-3, 10.0)
        _finite(f"{self.kind}: start_s", self.start_s, 0.0, MAX_START_S)
        _finite(f"{self.kind}: stop_within_m", self.stop_within_m, 0.0, MAX_STOP_M)
        if not isinstance(self.loop, bool):
            raise ActorError(f"{self.kind}: loop must be true or false")

    @classmethod
    def parse(cls, text: str, cfg) -> "Actor":
        """``KIND:X1,Y1;X2,Y2[;...][@SPEED_M_S][+START_S][/loop][/stop=M]`` (the ``--actor`` form).

        Without ``@SPEED_M_S`` the kind's ``actors.<kind>.speed_m_s`` of ``cfg``.
        """
        where = f"--actor {text!r}"
        kind, sep, rest = text.strip().partition(":")
        if not sep or kind not in KINDS:
            raise ActorError(
                f"{where}: expected KIND:X1,Y1;X2,Y2[@SPEED][+START][/loop][/stop=M] "
                f"with KIND one of {', '.join(KINDS)}"
            )
        rest, *flags = rest.split("/")
        loop, stop = False, 0.0
        try:
            for flag in flags:
                if flag == "loop":
                    loop = True
                elif flag.startswith("stop="):
                    stop = float(flag[5:])
                else:
                    raise ActorError(f"{where}: unknown flag /{flag} (allowed: /loop, /stop=M)")
            start = 0.0
            if "+" in rest:
                rest, start_text = rest.rsplit("+", 1)
                start = float(start_text)
            speed = getattr(cfg.actors, kind).speed_m_s
            if "@" in rest:
                rest, speed_text = rest.split("@", 1)
                speed = float(speed_text)
            points = []
            for pair in rest.split(";"):
                x, y = pair.split(",")
                points.append((float(x), float(y)))
        except ValueError as exc:
            if isinstance(exc, ActorError):
                raise
            raise ActorError(
                f"{where}: expected KIND:X1,Y1;X2,Y2[@SPEED][+START][/loop][/stop=M], "
                "numbers in m, m/s and s"
            ) from None
        try:
            return cls(kind, tuple(points), speed, start, loop, stop)
        except ActorError as exc:
            raise ActorError(f"{where}: {exc}") from None

    @classmethod
    def from_mapping(cls, tree, where: str) -> "Actor":
        """A mission's actor: ``{kind, waypoints_xy_m: [[x, y], ...], speed_m_s, start_s?, loop?,
        stop_within_m?}``."""
        fields = ("kind", "waypoints_xy_m", "speed_m_s", "start_s", "loop", "stop_within_m")
        if not isinstance(tree, dict):
            raise ActorError(f"{where}: expected a mapping with {', '.join(fields)}")
        unknown = [k for k in tree if k not in fields]
        if unknown:
            raise ActorError(f"{where}: unknown key {unknown[0]!r} (expected {', '.join(fields)})")
        for key in fields[:3]:
            if key not in tree:
                raise ActorError(f"{where}.{key} is missing")
        if tree["kind"] not in KINDS:
            raise ActorError(f"{where}.kind: {tree['kind']!r} must be one of {', '.join(KINDS)}")
        points = tree["waypoints_xy_m"]
        if not isinstance(points, list) or not all(
            isinstance(p, list) and len(p) == 2 for p in points
        ):
            raise ActorError(f"{where}.waypoints_xy_m: expected a list of [x, y] pairs in m")
        loop = tree.get("loop", False)
        if not isinstance(loop, bool):
            raise ActorError(f"{where}.loop: {loop!r} must be true or false")
        try:
            return cls(
                tree["kind"],
                tuple(tuple(p) for p in points),
                _finite(f"{where}.speed_m_s", tree["speed_m_s"]),
                _finite(f"{where}.start_s", tree.get("start_s", 0.0)),
                loop,
                _finite(f"{where}.stop_within_m", tree.get("stop_within_m", 0.0)),
            )
        except ActorError as exc:
            raise ActorError(f"{where}: {exc}") from None


def body_name(index: int, actor: Actor) -> str:
    """The mocap body (and collision report name) of actor ``index``: ``<kind>_<index>``."""
    return f"{actor.kind}_{index}"


def check_speeds(actors: tuple[Actor, ...], cfg) -> None:
    """Each actor's speed within its kind's sourced range (``actors.<kind>.speed_min/max_m_s``)."""
    for i, a in enumerate(actors):
        k = getattr(cfg.actors, a.kind)
        if not k.speed_min_m_s <= a.speed_m_s <= k.speed_max_m_s:
            raise ActorError(
                f"actor {i} ({body_name(i, a)}): speed {a.speed_m_s:g} m/s outside the {a.kind}'s "
                f"[{k.speed_min_m_s:g}, {k.speed_max_m_s:g}] m/s (actors.{a.kind}.speed_min_m_s, "
                "speed_max_m_s)"
            )


def footprint_half_m(kind: str, cfg) -> tuple[float, float]:
    """Half length (along its heading) and half width of an actor's footprint, m: everything of it
    that stands on the floor (a person's torso, wider than the legs; a jack's outline)."""
    if kind == "person":
        p = cfg.actors.person
        return max(p.torso_depth_m, 2 * p.leg_radius_m) / 2, max(
            p.torso_width_m, p.leg_spacing_m + 2 * p.leg_radius_m
        ) / 2
    j = cfg.actors.pallet_jack
    return j.length_m / 2, j.width_m / 2


def add_actors(spec, actors: tuple[Actor, ...], cfg) -> None:
    """Add each actor to the world ``spec`` (an ``mujoco.MjSpec``) as a mocap body at its pose at
    t = 0 (module notes); its geoms named ``<body>/<part>``, group 0."""
    from amr_twin.model.actor_bodies import add_pallet_jack, add_person
    from amr_twin.model.actor_paths import actor_path

    for i, actor in enumerate(actors):
        name = body_name(i, actor)
        x, y, yaw = actor_path(actor, cfg).pose_at(0.0)
        body = spec.worldbody.add_body(
            name=name,
            mocap=True,
            pos=[x, y, 0.0],
            quat=[math.cos(0.5 * yaw), 0.0, 0.0, math.sin(0.5 * yaw)],
        )
        (add_person if actor.kind == "person" else add_pallet_jack)(
            body, name, getattr(cfg.actors, actor.kind)
        )
