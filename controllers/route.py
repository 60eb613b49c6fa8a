"""Routes: a start pose and waypoints in a world's ``map`` frame, read from YAML.

A route is a polyline in the ``map`` frame: the start pose's position, then the
waypoints. Route files (YAML)::

    name: warehouse_60m
    # optional: a world of models/worlds/, or a file beside the route
    world: warehouse
    start_xy_yaw: [-7.5, 0.0, 0.0]      # x_m, y_m, yaw_rad of base_link at the start
    waypoints_xy_m: [[6.2, 0.0], [6.2, 5.5]]
    max_speed_m_s: 1.0                   # (0, 1]
    max_angular_rad_s: 1.0               # > 0
    lookahead_m: 0.8                     # > 0
    goal_tolerance_m: 0.2                # > 0

:func:`load_route` validates a file (one-line :class:`RouteError` naming the field);
:func:`route_length_m` and :func:`distance_to_path_m` measure against the polyline.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from amr_twin.model.yaml_file import read_yaml

MAX_ROUTE_SPEED_M_S = 1.0
"""Highest route speed accepted, m/s ('at up to 1 m/s' was asked)."""
ROUTE_FIELDS = (
    "name",
    "world",
    "start_xy_yaw",
    "waypoints_xy_m",
    "max_speed_m_s",
    "max_angular_rad_s",
    "lookahead_m",
    "goal_tolerance_m",
)


class RouteError(ValueError):
    """A route is invalid; the message is one line naming the field."""


@dataclass(frozen=True)
class Route:
    """A route: start pose, waypoints (the path is start -> waypoints) and follower limits.

    Attributes
    ----------
    name : str
    start_xy_yaw : tuple of 3 float
        Start pose of ``base_link`` in ``map``: x_m, y_m, yaw_rad.
    waypoints_xy_m : np.ndarray, shape (N, 2)
        Waypoints in ``map``, m; the last one is the goal.
    max_speed_m_s : float
        Linear speed limit, m/s, in (0, 1].
    max_angular_rad_s : float
        Yaw rate limit, rad/s, > 0.
    lookahead_m : float
        Pure-pursuit lookahead along the path, m, > 0.
    goal_tolerance_m : float
        Distance to the goal at which the route is done, m, > 0.
    world : str
        The world the route is drawn in: a name of ``models/worlds/`` or a file path
        (:func:`amr_twin.model.worlds.world_path`); its frame is the route's ``map``.
    """

    name: str
    start_xy_yaw: tuple[float, float, float]
    waypoints_xy_m: np.ndarray
    max_speed_m_s: float = MAX_ROUTE_SPEED_M_S
    max_angular_rad_s: float = 1.0
    lookahead_m: float = 0.8
    goal_tolerance_m: float = 0.2
    world: str = "warehouse"

    def __post_init__(self) -> None:
        try:
            start = tuple(float(v) for v in np.asarray(self.start_xy_yaw, dtype=float).ravel())
        except (TypeError, ValueError):
            start = ()
        if len(start) != 3 or not all(math.isfinite(v) for v in start):
            raise RouteError(
                f"start_xy_yaw: {self.start_xy_yaw!r} must be 3 finite numbers [x_m, y_m, yaw_rad]"
            )
        object.__setattr__(self, "start_xy_yaw", start)
        try:
            pts = np.array(self.waypoints_xy_m, dtype=float)
        except (TypeError, ValueError):
            raise RouteError("waypoints_xy_m: must be a list of [x_m, y_m] pairs") from None
        if pts.ndim != 2 or pts.shape[1] != 2 or len(pts) < 1:
            raise RouteError(f"waypoints_xy_m: shape {pts.shape} must be (N, 2) with N >= 1")
        if not np.isfinite(pts).all():
            raise RouteError("waypoints_xy_m: all coordinates must be finite")
        path = np.vstack([np.array(start[:2])[None], pts])
        if np.any(np.hypot(*np.diff(path, axis=0).T) < 1e-6):
            raise RouteError("waypoints_xy_m: consecutive points (start included) must differ")
        pts.setflags(write=False)
        object.__setattr__(self, "waypoints_xy_m", pts)
        limits = (
            ("max_speed_m_s", 0.0, MAX_ROUTE_SPEED_M_S),
            ("max_angular_rad_s", 0.0, math.inf),
            ("lookahead_m", 0.0, math.inf),
            ("goal_tolerance_m", 0.0, math.inf),
        )
        for name, low, high in limits:
            value = getattr(self, name)
            if (
                isinstance(value, bool)
                or not isinstance(value, (int, float))
                or not math.isfinite(value)
                or not low < value <= high
            ):
                allowed = f"({low:g}, {high:g}]" if math.isfinite(high) else f"> {low:g}"
                raise RouteError(f"{name}: {value!r} must be a finite number in {allowed}")
            object.__setattr__(self, name, float(value))

    def path_xy_m(self) -> np.ndarray:
        """The polyline ``(N + 1, 2)``: the start position, then the waypoints, m."""
        return np.vstack([np.array(self.start_xy_yaw[:2])[None], self.waypoints_xy_m])


def load_route(path: str | Path) -> Route:
    """Read and validate a route YAML file (module docstring); raises :class:`RouteError`."""
    path = Path(path)
    tree = read_yaml(path, "route", RouteError)
    if not isinstance(tree, dict):
        raise RouteError(f"route {path.name}: expected a mapping with {', '.join(ROUTE_FIELDS)}")
    unknown = [k for k in tree if k not in ROUTE_FIELDS]
    if unknown:
        raise RouteError(
            f"route {path.name}: unknown key {unknown[0]!r} (expected {', '.join(ROUTE_FIELDS)})"
        )
    for key in ("start_xy_yaw", "waypoints_xy_m"):
        if key not in tree:
            raise RouteError(f"route {path.name}: {key} is missing")
    world = tree.get("world", "warehouse")
    if not isinstance(world, str) or not world.strip():
        raise RouteError(f"route {path.name}: world: {world!r} must be a world name or a file path")
    tree["world"] = _world_of(world.strip(), path)
    try:
        return Route(**{"name": path.stem, **tree})
    except RouteError as exc:
        raise RouteError(f"route {path.name}: {exc}") from None


def _world_of(world: str, route_path: Path) -> str:
    """A route's ``world``: a name of ``models/worlds/`` as it is, a file resolved beside the route;
    must exist."""
    from amr_twin.model.worlds import world_path

    path = world_path(world)
    if Path(world).suffix:
        path = path if path.is_absolute() else (route_path.parent / path)
    if not path.is_file():
        raise RouteError(
            f"route {route_path.name}: world: {world!r} is not a world of models/worlds/ nor a "
            f"file "
            f"({path} does not exist)"
        )
    return world if not Path(world).suffix else str(path)


def route_length_m(route: Route) -> float:
    """Length of the route's polyline from the start through every waypoint, m."""
    return float(np.sum(np.hypot(*np.diff(route.path_xy_m(), axis=0).T)))


def distance_to_path_m(route: Route, xy_m: np.ndarray) -> np.ndarray:
    """Distance ``(K,)`` from each point of ``xy_m (K, 2)`` to the nearest point of the route
    polyline, m."""
    p = np.atleast_2d(np.asarray(xy_m, dtype=float))[:, None, :]
    path = route.path_xy_m()
    a, ab = path[:-1], np.diff(path, axis=0)
    u = np.clip(((p - a) * ab).sum(2) / (ab * ab).sum(1), 0.0, 1.0)  # (K, segments)
    return np.linalg.norm(p - (a + u[..., None] * ab), axis=2).min(1)


def check_in_free_space(route: Route, boxes, half_width_m: float, world: str = "") -> None:
    """Refuse a route the robot cannot drive in its world: a start or waypoint outside the world's
    extent (the box hull of its geoms at the robot's height), a point where the robot's footprint
    (``half_width_m``) meets a geom, or a path crossing one. ``boxes``: the world's
    :class:`~amr_twin.model.world_geometry.Footprints`; a world without any (``empty``) has no
    extent. Raises :class:`RouteError` naming the route, the point and the world.
    """
    from amr_twin.model.world_geometry import distance_to_boxes_m

    if len(boxes) == 0:
        return
    c, s = np.abs(np.cos(boxes.yaw_rad)), np.abs(np.sin(boxes.yaw_rad))
    hx, hy = boxes.half_xy_m.T
    reach = np.stack(
        [c * hx + s * hy, s * hx + c * hy], axis=1
    )  # (K, 2): each box's half extent along x, y
    lo, hi = (boxes.centre_xy_m - reach).min(0), (boxes.centre_xy_m + reach).max(0)
    names = ["start_xy_yaw"] + [f"waypoints_xy_m[{i}]" for i in range(len(route.waypoints_xy_m))]
    where = f" of {world}" if world else ""
    for name, (x, y) in zip(names, route.path_xy_m()):
        if not (lo[0] <= x <= hi[0] and lo[1] <= y <= hi[1]):
            raise RouteError(
                f"route {route.name}: {name} ({x:g}, {y:g}) lies outside the world{where}: its "
                f"walls "
                f"span x {lo[0]:.1f} to {hi[0]:.1f} m, y {lo[1]:.1f} to {hi[1]:.1f} m"
            )
        gaps = [
            float(distance_to_boxes_m(np.array([[x, y]]), boxes[k : k + 1])[0])
            for k in range(len(boxes))
        ]
        k = int(np.argmin(gaps))
        if gaps[k] < half_width_m:
            raise RouteError(
                f"route {route.name}: {name} ({x:g}, {y:g}) is {gaps[k]:.2f} m from "
                f"{boxes.names[k]}"
                f"{where}; the robot needs {half_width_m:.2f} m (its half width)"
            )
    path = route.path_xy_m()
    for i, (a, b) in enumerate(zip(path[:-1], path[1:])):
        n = max(2, int(np.ceil(np.hypot(*(b - a)) / 0.05)) + 1)
        points = a + np.linspace(0.0, 1.0, n)[:, None] * (b - a)
        if (distance_to_boxes_m(points, boxes) == 0.0).any():
            raise RouteError(
                f"route {route.name}: the leg to {names[i + 1]} ({b[0]:g}, {b[1]:g}) crosses a "
                f"geom{where}"
            )
