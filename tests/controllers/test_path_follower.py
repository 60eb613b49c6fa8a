"""Routes, pure pursuit on a kinematic robot, the cmd_vel node, and one short drive in the twin."""

import math
import xml.etree.ElementTree as ET
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from amr_twin.ros.bus import Bus
from amr_twin.base.clock import VirtualClock
from amr_twin.controllers.path_follower import PathFollowerNode, PurePursuit
from amr_twin.controllers.route import (
    Route,
    RouteError,
    distance_to_path_m,
    load_route,
    route_length_m,
)
from amr_twin.ros.geometry_messages import Twist
from amr_twin.recording.recorder import attach_recorder, recorder_of

ROOT = Path(__file__).resolve().parents[2]
DEFAULT_ROUTE = ROOT / "experiments" / "routes" / "warehouse_60m.yaml"
WAREHOUSE = ROOT / "models" / "worlds" / "warehouse.xml"
CLEARANCE_M = 0.8


def _world_boxes(path: Path = WAREHOUSE) -> list[tuple[str, float, float, float, float, float]]:
    """Box footprints of an MJCF world, default classes resolved: (name, x, y, half_x, half_y,
    yaw_rad)."""
    root = ET.parse(path).getroot()
    defaults = {
        d.get("class"): d.find("geom").attrib
        for d in root.iter("default")
        if d.get("class") and d.find("geom") is not None
    }
    boxes = []
    for g in root.find("worldbody").iter("geom"):
        a = {**defaults.get(g.get("class"), {}), **g.attrib}
        if a.get("type") != "box":
            continue
        x, y, _ = (float(v) for v in a["pos"].split())
        hx, hy, _ = (float(v) for v in a["size"].split())
        yaw = math.radians(float(a.get("euler", "0 0 0").split()[2]))  # MJCF angles in degrees
        boxes.append((a["name"], x, y, hx, hy, yaw))
    return boxes


def _clearance_m(xy: np.ndarray, boxes) -> np.ndarray:
    """Distance (K,) from each point to the nearest box footprint, m."""
    xy = np.atleast_2d(xy)
    best = np.full(len(xy), np.inf)
    for _, cx, cy, hx, hy, yaw in boxes:
        c, s = math.cos(yaw), math.sin(yaw)
        dx, dy = xy[:, 0] - cx, xy[:, 1] - cy
        lx, ly = c * dx + s * dy, -s * dx + c * dy
        best = np.minimum(
            best, np.hypot(np.maximum(np.abs(lx) - hx, 0), np.maximum(np.abs(ly) - hy, 0))
        )
    return best


def _densify(path: np.ndarray, step_m: float = 0.01) -> np.ndarray:
    parts = [
        path[i]
        + np.linspace(0, 1, max(2, int(np.hypot(*(path[i + 1] - path[i])) / step_m)))[:, None]
        * (path[i + 1] - path[i])
        for i in range(len(path) - 1)
    ]
    return np.vstack(parts)


def _drive_kinematic(
    route: Route, dt_s: float = 0.05, t_max_s: float = 200.0, pose=None, **pursuit
):
    """Unicycle driven by PurePursuit: rows (t_s, x_m, y_m, yaw_rad, v, w, progress_m), done."""
    pp = PurePursuit(route, **pursuit)
    x, y, yaw = pose if pose is not None else route.start_xy_yaw
    rows, t = [], 0.0
    while t < t_max_s:
        v, w, done = pp.command(x, y, yaw)
        rows.append((t, x, y, yaw, v, w, pp.progress_m))
        if done:
            break
        x += v * dt_s * math.cos(yaw + 0.5 * w * dt_s)
        y += v * dt_s * math.sin(yaw + 0.5 * w * dt_s)
        yaw += w * dt_s
        t += dt_s
    return np.array(rows), pp.done


# -- routes ---------------------------------------------------------------------------
def test_default_route_is_about_60_m_in_the_warehouse():
    route = load_route(DEFAULT_ROUTE)
    assert route.name == "warehouse_60m"
    assert 55.0 <= route_length_m(route) <= 65.0
    assert route.max_speed_m_s <= 1.0
    assert route.start_xy_yaw == pytest.approx((-7.5, 0.0, 0.0))


def test_default_route_keeps_clearance_from_every_world_geom():
    boxes = _world_boxes()
    names = {b[0] for b in boxes}
    assert {
        "wall_north",
        "rack_n_beam_low",
        "rack_s_u0",
        "pallet_3",
    } <= names  # the parser saw the world
    pts = _densify(load_route(DEFAULT_ROUTE).path_xy_m())
    clearance = _clearance_m(pts, boxes)
    assert clearance.min() >= CLEARANCE_M, f"{clearance.min():.3f} m at {pts[clearance.argmin()]}"
    # the check can fail: a leg through the rotated pallet's corner at (-7.78, -1.55) would
    assert _clearance_m(np.array([[-7.5, -1.5]]), boxes)[0] < CLEARANCE_M


def test_corridor_route_keeps_clearance_and_runs_the_corridor():
    route = load_route(ROOT / "experiments" / "routes" / "corridor.yaml")
    assert route.world == "corridor"
    boxes = _world_boxes(ROOT / "models" / "worlds" / "corridor.xml")
    walls = [b for b in boxes if b[0].startswith("corridor_")]
    others = [b for b in boxes if not b[0].startswith("corridor_")]
    assert len(walls) == 3 and {"rack_s_u0", "pallet_3", "wall_east_n"} <= {b[0] for b in others}
    pts = _densify(route.path_xy_m())
    assert _clearance_m(pts, others).min() >= CLEARANCE_M
    assert _clearance_m(pts, walls).min() >= 1.0  # the corridor is 2.2 m wide
    in_corridor = pts[pts[:, 0] > 10.2]
    assert np.ptp(in_corridor[:, 0]) > 30.0  # a long straight inside it (and back)
    assert 100.0 < route_length_m(route) < 125.0


def test_route_world_must_exist(tmp_path):
    text = DEFAULT_ROUTE.read_text()
    bad = tmp_path / "r.yaml"
    bad.write_text(text + "world: nowhere\n")
    with pytest.raises(RouteError, match="world"):
        load_route(bad)
    (tmp_path / "w.xml").write_text((ROOT / "models" / "worlds" / "corridor.xml").read_text())
    bad.write_text(text + "world: w.xml\n")  # a file beside the route
    assert load_route(bad).world == str(tmp_path / "w.xml")


def test_slows_down_before_a_reversal_and_rounds_right_angles_at_speed():
    reverse = Route("rev", (0.0, 0.0, 0.0), [[10.0, 0.0], [4.0, 0.0]])
    rows, done = _drive_kinematic(reverse)
    assert done
    turning = np.flatnonzero((rows[:, 4] == 0.0) & (rows[:, 5] != 0.0))
    first = turning[0]
    assert rows[first, 1] > 9.0  # the turn in place is at the reversal
    assert rows[first - 1, 4] <= 0.15  # ... reached at a crawl, not at 1 m/s
    assert rows[:first, 4].max() == pytest.approx(1.0)
    # a right angle is rounded at speed, no stop and no turn in place
    square = Route("l", (0.0, 0.0, 0.0), [[10.0, 0.0], [10.0, 10.0]])
    rows, done = _drive_kinematic(square)
    near = np.hypot(rows[:, 1] - 10.0, rows[:, 2]) < 1.0
    assert done and rows[near, 4].min() > 0.3


def test_route_length_counts_the_start():
    route = Route("l", (0.0, 0.0, 0.0), np.array([[3.0, 4.0], [3.0, 0.0]]))
    assert route_length_m(route) == pytest.approx(9.0)
    assert distance_to_path_m(
        route, np.array([[1.5, 2.0], [4.0, 2.0], [-1.0, 0.0]])
    ) == pytest.approx([0.0, 1.0, 1.0])


@pytest.mark.parametrize(
    "edit, field",
    [
        ({"max_speed_m_s": 1.5}, "max_speed_m_s"),
        ({"max_speed_m_s": 0}, "max_speed_m_s"),
        ({"lookahead_m": -1.0}, "lookahead_m"),
        ({"goal_tolerance_m": ".nan"}, "goal_tolerance_m"),
        ({"max_angular_rad_s": "fast"}, "max_angular_rad_s"),
        ({"start_xy_yaw": [0.0, 1.0]}, "start_xy_yaw"),
        ({"start_xy_yaw": "home"}, "start_xy_yaw"),
        ({"waypoints_xy_m": [[1.0, 2.0, 3.0]]}, "waypoints_xy_m"),
        ({"waypoints_xy_m": [[0.0, 0.0]]}, "waypoints_xy_m"),  # same as the start
        ({"speed": 1.0}, "unknown key 'speed'"),
    ],
)
def test_bad_route_file_gives_one_line_error_naming_the_field(tmp_path, edit, field):
    tree = {"start_xy_yaw": [0.0, 0.0, 0.0], "waypoints_xy_m": [[2.0, 0.0]], **edit}
    text = "\n".join(f"{k}: {v}" for k, v in tree.items())
    path = tmp_path / "r.yaml"
    path.write_text(text)
    with pytest.raises(RouteError, match=field) as info:
        load_route(path)
    assert "\n" not in str(info.value) and "r.yaml" in str(info.value)


def test_missing_route_file_and_missing_field(tmp_path):
    with pytest.raises(RouteError, match="nope.yaml"):
        load_route(tmp_path / "nope.yaml")
    (tmp_path / "r.yaml").write_text("start_xy_yaw: [0, 0, 0]\n")
    with pytest.raises(RouteError, match="waypoints_xy_m is missing"):
        load_route(tmp_path / "r.yaml")


# -- pure pursuit ---------------------------------------------------------------------
STRAIGHT = Route("straight", (0.0, 0.0, 0.0), np.array([[10.0, 0.0]]))


def test_on_the_path_it_drives_straight_at_full_speed():
    v, w, done = PurePursuit(STRAIGHT).command(0.0, 0.0, 0.0)
    assert (v, w, done) == (pytest.approx(1.0), pytest.approx(0.0), False)


def test_left_of_the_path_it_steers_right_with_pure_pursuit_curvature():
    pp = PurePursuit(STRAIGHT)
    v, w, _ = pp.command(0.0, 0.3, 0.0)
    # lookahead point 0.8 m along the path from the projection (0, 0): (0.8, 0) seen from (0, 0.3)
    alpha, d = math.atan2(-0.3, 0.8), math.hypot(0.8, 0.3)
    assert w / v == pytest.approx(2 * math.sin(alpha) / d)
    assert w < 0 and pp.cross_track_m == pytest.approx(0.3)


def test_non_finite_pose_is_refused():
    with pytest.raises(ValueError, match="^pose"):
        PurePursuit(STRAIGHT).command(0.0, math.nan, 0.0)


def test_facing_away_it_turns_in_place_toward_the_path():
    v, w, done = PurePursuit(STRAIGHT).command(
        0.0, 0.0, math.radians(100)
    )  # path is 100 deg to the right
    assert v == 0.0 and w == pytest.approx(-1.0) and not done


def test_speed_limited_by_yaw_rate_on_a_tight_bearing():
    route = replace(STRAIGHT, max_angular_rad_s=0.5)
    v, w, _ = PurePursuit(route).command(
        0.0, 0.0, math.radians(-40)
    )  # 40 deg bearing: curvature 1.6 /m
    assert abs(w) == pytest.approx(0.5) and v == pytest.approx(
        0.5 / (2 * math.sin(math.radians(40)) / 0.8)
    )


def test_slows_down_near_the_goal_then_stops_done():
    rows, done = _drive_kinematic(STRAIGHT)
    assert done
    x, v = rows[:, 1], rows[:, 4]
    assert v[x < 5.0].min() == pytest.approx(1.0)
    assert v[(x > 9.6) & (v > 0)].max() < 0.7  # decelerating for the goal
    assert x[-1] == pytest.approx(10.0, abs=STRAIGHT.goal_tolerance_m)
    pp = PurePursuit(STRAIGHT)
    assert not any(pp.command(x_m, 0.0, 0.0)[2] for x_m in np.arange(0.0, 9.7, 0.5))
    assert pp.command(9.9, 0.0, 0.0)[2] and pp.command(0.0, 0.0, 0.0) == (0.0, 0.0, True)  # latched


def test_kinematic_robot_follows_the_default_route_within_limits():
    route = load_route(DEFAULT_ROUTE)
    rows, done = _drive_kinematic(route)
    assert done
    v, w, progress = rows[:, 4], rows[:, 5], rows[:, 6]
    assert (
        v.max() <= route.max_speed_m_s + 1e-12
        and np.abs(w).max() <= route.max_angular_rad_s + 1e-12
    )
    assert progress[-1] == pytest.approx(
        route_length_m(route), abs=route.lookahead_m + route.goal_tolerance_m
    )
    xte = distance_to_path_m(route, rows[:, 1:3])
    assert xte.max() < 0.35  # corner rounding by the lookahead
    assert _clearance_m(rows[:, 1:3], _world_boxes()).min() > 0.6
    assert rows[-1, 0] < 1.3 * route_length_m(route) / route.max_speed_m_s


def test_progress_is_not_captured_by_a_crossing_branch():
    # a figure-eight: the second diagonal crosses the first at (5, 0)
    route = Route(
        "eight",
        (0.0, -2.0, math.radians(22)),
        np.array([[10.0, 2.0], [10.0, -2.0], [0.0, 2.0], [0.0, -2.0]]),
        lookahead_m=0.8,
    )
    rows, done = _drive_kinematic(route)
    assert done
    progress = rows[:, 6]
    # no jump to the other branch (at the crossing it would be about 10 m); cutting a sharp corner
    # moves it up to ~0.5 m
    assert 0.0 <= np.diff(progress).min() and np.diff(progress).max() < 1.0
    # at the crossing, a robot 7 cm off the first branch lies exactly on the second one
    pp = PurePursuit(route)
    for x_m in np.arange(0.0, 4.6, 0.25):
        pp.command(x_m, -2.0 + 0.4 * x_m, route.start_xy_yaw[2])
    pp.command(4.907, 0.037, route.start_xy_yaw[2])
    assert 5.0 < pp.progress_m < 6.0  # still on the first branch (the second passes here at ~20 m)
    # it drove through every corner, in order
    visits = [np.argmin(np.hypot(*(rows[:, 1:3] - c).T)) for c in route.waypoints_xy_m[:3]]
    assert visits == sorted(visits)
    assert distance_to_path_m(route, rows[:, 1:3]).max() < 0.5


# -- the node -------------------------------------------------------------------------
def test_node_publishes_cmd_vel_at_its_rate_and_zero_when_done():
    clock = VirtualClock()
    bus = Bus(clock)
    got: list[tuple[int, Twist]] = []
    bus.subscribe("cmd_vel", lambda m: got.append((clock.now_us, m)))
    pose = [0.0, 0.0, 0.0]
    route = Route("short", (0.0, 0.0, 0.0), np.array([[2.0, 0.0]]))
    node = PathFollowerNode(bus, clock, route, pose_source=lambda: tuple(pose), rate_hz=20.0)
    clock.run_until(1_000_000)
    assert len(got) == 21 and got[1][0] - got[0][0] == 50_000  # t = 0, 0.05, ..., 1.0 s
    assert got[-1][1].linear.x == pytest.approx(1.0) and not node.done
    pose[0] = 1.9
    clock.run_until(1_100_000)
    assert node.done and got[-1][1].linear.x == 0.0 and got[-1][1].angular.z == 0.0
    h = node.history()
    assert h["t_s"].shape == (len(got),) and h["linear_m_s"][-1] == 0.0
    node.shutdown()
    clock.run_until(2_000_000)
    assert len(got) == len(h["t_s"])
    with pytest.raises(ValueError, match="rate_hz"):
        PathFollowerNode(bus, clock, STRAIGHT, pose_source=lambda: (0.0, 0.0, 0.0), rate_hz=0.0)


# -- in the twin ----------------------------------------------------------------------
def test_twin_rounds_the_first_rack_corners_without_touching_anything():
    """The default route's two corners around the north rack's east end, improved firmware, true
    pose."""
    mujoco = pytest.importorskip("mujoco")
    from amr_twin.model.config import load_config
    from amr_twin.controllers.diff_drive import DiffDriveNode
    from amr_twin.assembly.twin import Twin, TwinOptions

    full = load_route(DEFAULT_ROUTE)
    route = replace(
        full,
        name="corner",
        start_xy_yaw=(3.0, 0.0, 0.0),
        waypoints_xy_m=np.vstack([full.waypoints_xy_m[:2], [[3.0, 5.5]]]),
    )
    twin = Twin(
        load_config(),
        TwinOptions(firmware="improved", world="warehouse", start_xy_yaw=route.start_xy_yaw),
    )
    attach_recorder(twin)
    DiffDriveNode(twin.bus, twin.clock, twin.client)
    m, d = twin.physics.model, twin.physics.data
    floor = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_GEOM, "floor")
    touches = []

    def true_pose():
        for i in range(d.ncon):  # robot geom against a world geom other than the floor
            g1, g2 = d.contact[i].geom1, d.contact[i].geom2
            if (m.geom_bodyid[g1] == 0) != (m.geom_bodyid[g2] == 0) and floor not in (g1, g2):
                touches.append((twin.t_s, g1, g2))
        p = twin.physics.pose()
        return p.x_m, p.y_m, p.yaw_rad

    node = PathFollowerNode(twin.bus, twin.clock, route, pose_source=true_pose)
    while not node.done and twin.t_s < 30.0:
        twin.advance(1.0)
    s = recorder_of(twin).series()
    assert node.done, f"not at the goal after {twin.t_s} s: {s.pose[-1]}"
    assert np.hypot(*(s.pose[-1, :2] - route.waypoints_xy_m[-1])) < 0.35
    xte = distance_to_path_m(route, s.pose[:, :2])
    assert xte.max() < 0.3 and np.sqrt(np.mean(xte**2)) < 0.1
    assert not touches
    # the inside of both corners is the rack's corner (4.85, 4.15): base_link stays well away
    assert _clearance_m(s.pose[:, :2], _world_boxes()).min() > 1.0
