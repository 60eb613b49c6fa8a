"""Actors as the model builds them: their paths in time (hand-computed poses), their bodies and
geoms (what a 0.45 m scan plane cuts), the parsing of --actor and a mission's actors, the free-space
check, and random actors drawn from a seed."""

import math

import mujoco
import numpy as np
import pytest

from amr_twin.model.actor_paths import actor_path
from amr_twin.model.actor_space import (
    check_paths,
    obstacle_boxes,
    overlapping,
    path_poses,
    random_actors,
)
from amr_twin.model.actors import Actor, ActorError, add_actors, check_speeds, footprint_half_m
from amr_twin.model.build import build
from amr_twin.model.world_spec import world_model
from amr_twin.model.config import load_config

CFG = load_config()
W = CFG.actors.person.turn_rate_rad_s  # 2 rad/s
LIDAR_Z_M = CFG.components.lidar.pos_m[2]  # the scan plane's height above the floor (robot level)


def test_an_actor_walks_its_waypoints_at_its_speed_and_turns_at_the_corners():
    """(0,0) -> (4,0) -> (4,3) at 1 m/s: positions and headings at times worked out by hand."""
    path = actor_path(Actor("person", ((0, 0), (4, 0), (4, 3)), 1.0), CFG)
    turn_s = (math.pi / 2) / W
    expected = {
        0.0: (0, 0, 0),
        1.5: (1.5, 0, 0),
        4.0: (4, 0, 0),
        4.0 + turn_s / 2: (4, 0, math.pi / 4),  # half way round the corner
        4.0 + turn_s + 1.0: (4, 1, math.pi / 2),
        4.0 + turn_s + 2.5: (4, 2.5, math.pi / 2),
        4.0 + turn_s + 3.0: (4, 3, math.pi / 2),
        100.0: (4, 3, math.pi / 2),
    }  # then it stands there
    for t, want in expected.items():
        assert path.pose_at(t) == pytest.approx(want, abs=1e-12), t
    assert path.duration_s == pytest.approx(7 + turn_s)


def test_a_loop_closes_back_to_the_first_waypoint_and_repeats():
    path = actor_path(Actor("person", ((0, 0), (3, 0), (3, 4)), 1.0, loop=True), CFG)
    back = math.atan2(-4, -3)  # heading of the closing segment
    t_corner2 = 3 + (math.pi / 2) / W + 4
    turn2 = abs(math.remainder(back - math.pi / 2, 2 * math.pi)) / W
    t_home = t_corner2 + turn2 + 5  # 5 m back to the start
    period = t_home + abs(back) / W  # and the turn to the first heading
    assert path.period_s == pytest.approx(period)
    assert path.pose_at(t_corner2 + turn2 + 2.5)[:2] == pytest.approx((1.5, 2.0))  # half way home
    assert path.pose_at(period + 1.0) == pytest.approx(path.pose_at(1.0))  # round again
    assert path.pose_at(2 * period + 1.0)[:2] == pytest.approx((1.0, 0.0))


def test_one_waypoint_stands_still_facing_x():
    path = actor_path(Actor("pallet_jack", ((2.0, -1.0),), 1.0), CFG)
    assert path.pose_at(0.0) == path.pose_at(50.0) == (2.0, -1.0, 0.0)


def test_parse_reads_the_cli_form():
    a = Actor.parse("person:1,2;3,4.5@1.2+3/loop/stop=1", CFG)
    assert a == Actor("person", ((1, 2), (3, 4.5)), 1.2, 3.0, True, 1.0)
    b = Actor.parse("pallet_jack:0,0;2,0", CFG)
    assert b.speed_m_s == CFG.actors.pallet_jack.speed_m_s and b.start_s == 0 and not b.loop


@pytest.mark.parametrize(
    "text, words",
    [
        ("robot:0,0;1,1", "KIND"),
        ("person:0,0;1", "expected"),
        ("person:0,0;1,1@fast", "expected"),
        ("person:0,0;0,0", "coincide"),
        ("person:0,0/loop", "two distinct"),
        ("person:0,0;1,1/jump", "unknown flag"),
        ("person:0,0;1,1@-1", "speed_m_s"),
        ("person:0,0;1,nan", "finite"),
        ("person:0,0;1,1+-2", "start_s"),
    ],
)
def test_parse_refuses_bad_text_in_one_line(text, words):
    with pytest.raises(ActorError) as err:
        Actor.parse(text, CFG)
    assert words in str(err.value) and "\n" not in str(err.value) and text in str(err.value)


def test_a_mission_actor_needs_kind_waypoints_and_speed():
    a = Actor.from_mapping(
        {"kind": "person", "waypoints_xy_m": [[0, 0], [2, 0]], "speed_m_s": 1.0, "loop": True},
        "actors[0]",
    )
    assert a.loop and a.waypoints_xy_m == ((0.0, 0.0), (2.0, 0.0))
    for tree, words in (
        ({"kind": "person", "waypoints_xy_m": [[0, 0]]}, "actors[0].speed_m_s is missing"),
        ({"kind": "dog", "waypoints_xy_m": [[0, 0]], "speed_m_s": 1}, "actors[0].kind"),
        ({"kind": "person", "waypoints_xy_m": [0, 0], "speed_m_s": 1}, "waypoints_xy_m"),
        (
            {"kind": "person", "waypoints_xy_m": [[0, 0]], "speed_m_s": 1, "colour": 1},
            "unknown key",
        ),
        (
            {"kind": "person", "waypoints_xy_m": [[0, 0], [1, 0]], "speed_m_s": 1, "loop": "y"},
            "loop",
        ),
    ):
        with pytest.raises(ActorError, match=__import__("re").escape(words)):
            Actor.from_mapping(tree, "actors[0]")


def test_speeds_outside_the_kinds_sourced_range_are_refused():
    check_speeds(
        (Actor("person", ((0, 0), (1, 0)), 1.8), Actor("pallet_jack", ((0, 0), (1, 0)), 0.5)), CFG
    )
    for actor, words in (
        (Actor("person", ((0, 0), (1, 0)), 1.9), "[0.5, 1.8]"),
        (Actor("pallet_jack", ((0, 0), (1, 0)), 1.6), "[0.5, 1.5]"),
    ):
        with pytest.raises(ActorError, match=__import__("re").escape(words)):
            check_speeds((actor,), CFG)


@pytest.fixture(scope="module")
def built():
    actors = (
        Actor("person", ((-3.0, 1.0), (-3.0, -1.0)), 1.0),
        Actor("pallet_jack", ((0.0, 1.5), (3.0, 1.5)), 1.0),
    )
    return build(CFG, "warehouse", (-6, 0, 0), visuals=False, imu=False, actors=actors).model


def _geoms(m, body):
    b = m.body(body).id
    return [g for g in range(m.ngeom) if m.geom_bodyid[g] == b]


def _z_span(m, g):
    """Bottom and top of geom ``g`` (an upright box or cylinder), m."""
    z, half = (
        m.geom_pos[g][2],
        (m.geom_size[g][2] if m.geom_type[g] == mujoco.mjtGeom.mjGEOM_BOX else m.geom_size[g][1]),
    )
    return z - half, z + half


def test_actors_are_mocap_bodies_at_their_start_in_the_lidars_group(built):
    m = built
    d = mujoco.MjData(m)
    mujoco.mj_forward(m, d)
    for name, xy in (("person_0", (-3.0, 1.0)), ("pallet_jack_1", (0.0, 1.5))):
        b = m.body(name).id
        assert m.body_mocapid[b] >= 0 and d.xpos[b][:2] == pytest.approx(xy)
        assert all(m.geom_group[g] == 0 for g in _geoms(m, name))
    yaw = math.atan2(
        2 * d.xquat[m.body("person_0").id][3] * d.xquat[m.body("person_0").id][0],
        1 - 2 * d.xquat[m.body("person_0").id][3] ** 2,
    )
    assert yaw == pytest.approx(-math.pi / 2)  # facing down its first segment (-y)


def test_the_scan_plane_cuts_a_persons_legs_and_a_jacks_pump_not_its_forks(built):
    """What the LiDAR can see: the geoms that span the plane's height, and those that collide."""
    m = built
    cut = {
        m.geom(g).name: _z_span(m, g)[0] <= LIDAR_Z_M <= _z_span(m, g)[1]
        for body in ("person_0", "pallet_jack_1")
        for g in _geoms(m, body)
        if m.geom_type[g] != 2
    }
    assert cut["person_0/leg_left"] and cut["person_0/leg_right"] and not cut["person_0/torso"]
    assert (
        cut["pallet_jack_1/pump"]
        and not cut["pallet_jack_1/fork_left"]
        and not cut["pallet_jack_1/frame"]
    )
    forks = [g for g in _geoms(m, "pallet_jack_1") if "fork" in m.geom(g).name]
    assert all(
        _z_span(m, g)[1] == pytest.approx(CFG.actors.pallet_jack.fork_height_m) for g in forks
    )
    collide = {
        m.geom(g).name
        for body in ("person_0", "pallet_jack_1")
        for g in _geoms(m, body)
        if m.geom_contype[g]
    }
    assert {
        "person_0/leg_left",
        "person_0/leg_right",
        "pallet_jack_1/fork_left",
        "pallet_jack_1/pump",
    } <= collide
    legs = [m.geom("person_0/leg_left").id, m.geom("person_0/leg_right").id]
    assert abs(m.geom_pos[legs[0]][1] - m.geom_pos[legs[1]][1]) == pytest.approx(
        CFG.actors.person.leg_spacing_m
    )


def test_a_path_through_a_rack_or_off_the_floor_is_refused_before_the_run():
    through = Actor(
        "person", ((-4.5, 2.0), (-4.5, 5.0)), 1.0
    )  # across the north rack row at y 3.0-4.1
    with pytest.raises(
        ActorError, match=r"actor 0 \(person_0\): its path runs into rack_n_.*near \(-4\.50, 2\.8"
    ):
        build(CFG, "warehouse", (-6, 0, 0), visuals=False, imu=False, actors=(through,))
    turning = Actor(
        "pallet_jack", ((-1.5, 1.5), (1.0, 1.5), (1.0, -1.0)), 1.0
    )  # its 1.55 m swings at the corner
    poses = path_poses(turning, CFG)
    assert (
        np.ptp(poses[:, 2]) == pytest.approx(math.pi / 2) and len(poses) > 2.5 / 0.05 + 2.5 / 0.05
    )
    with pytest.raises(ActorError, match="leaves the floor"):
        build(
            CFG,
            "empty",
            (0, 0, 0),
            visuals=False,
            imu=False,
            actors=(Actor("person", ((0, 3), (49.9, 3)), 1.0),),
        )
    model = world_model(CFG, "warehouse")
    check_paths(
        model, (Actor("person", ((-4.5, 2.5), (-4.5, -2.5)), 1.0), turning), CFG
    )  # the aisle is free


def test_the_overlap_test_agrees_with_shapely_on_random_rectangles():
    """The separating-axis test against an independent polygon intersection."""
    shapely = pytest.importorskip("shapely")
    from shapely.geometry import Polygon

    from amr_twin.model.world_geometry import Footprints

    rng = np.random.default_rng(3)

    def rect(x, y, hx, hy, yaw):
        c, s = math.cos(yaw), math.sin(yaw)
        return Polygon(
            [
                (x + c * a - s * b, y + s * a + c * b)
                for a, b in ((-hx, -hy), (hx, -hy), (hx, hy), (-hx, hy))
            ]
        )

    boxes = Footprints(
        rng.uniform(-3, 3, (20, 2)),
        rng.uniform(0.05, 1.0, (20, 2)),
        rng.uniform(-3, 3, 20),
        tuple(f"b{i}" for i in range(20)),
    )
    poses = np.column_stack([rng.uniform(-4, 4, (500, 2)), rng.uniform(-3, 3, 500)])
    got = overlapping(poses, (0.8, 0.3), boxes) >= 0
    polys = [rect(*c, *h, y) for c, h, y in zip(boxes.centre_xy_m, boxes.half_xy_m, boxes.yaw_rad)]
    want = np.array(
        [any(rect(x, y, 0.8, 0.3, a).intersects(p) for p in polys) for x, y, a in poses]
    )
    assert 50 < want.sum() < 450 and np.array_equal(got, want)
    assert shapely is not None


def test_obstacles_are_the_static_world_up_to_the_actors_height(built):
    boxes = obstacle_boxes(built, CFG.actors.person.height_m)
    assert (
        "rack_n_beam_high" in boxes.names
        and "wall_north" in boxes.names
        and "floor" not in boxes.names
    )
    assert not any(n.startswith(("person_", "pallet_jack", "amr/", "geom")) for n in boxes.names)
    assert any(n.startswith("pallet") for n in boxes.names)  # the loose pallets, 0.15 m tall
    assert "rack_n_beam_high" not in obstacle_boxes(built, 1.2).names  # a beam at 1.45-1.55 m


def test_random_actors_are_the_same_for_a_seed_different_for_another_and_on_free_space():
    model = world_model(CFG, "warehouse")
    a = random_actors(model, 4, 7, CFG, (-6.0, 0.0))
    assert a == random_actors(model, 4, 7, CFG, (-6.0, 0.0))
    b = random_actors(model, 4, 8, CFG, (-6.0, 0.0))
    assert a != b and all(x.waypoints_xy_m != y.waypoints_xy_m for x, y in zip(a, b))
    check_paths(model, a + b, CFG)
    check_speeds(a + b, CFG)
    assert all(x.loop and len(x.waypoints_xy_m) == 4 for x in a + b)
    for x in a + b:  # every start clear of the robot's footprint
        assert (
            math.dist(x.waypoints_xy_m[0], (-6.0, 0.0))
            > math.hypot(*footprint_half_m(x.kind, CFG)) + 1.0
        )
    kinds = [x.kind for seed in range(6) for x in random_actors(model, 4, seed, CFG, (-6.0, 0.0))]
    assert 8 < kinds.count("person") < 24 and "pallet_jack" in kinds  # 3 in 4 people


def test_add_actors_places_every_kind_in_any_spec():
    spec = mujoco.MjSpec()
    spec.worldbody.add_geom(type=mujoco.mjtGeom.mjGEOM_PLANE, size=[5, 5, 0.1])
    add_actors(
        spec,
        (Actor("person", ((1, 1), (2, 1)), 1.0), Actor("pallet_jack", ((0, -2), (0, 2)), 1.0)),
        CFG,
    )
    m = spec.compile()
    assert (
        m.nmocap == 2 and m.body("pallet_jack_1").geomnum == 6 and m.body("person_0").geomnum == 4
    )


def test_the_scan_planes_walls_leave_the_actors_out():
    """A jack's frame cut at 0.15 m: not a wall of the world's map (it moves)."""
    from amr_twin.model.world_geometry import scan_plane_boxes

    jack = (Actor("pallet_jack", ((0.0, 1.5), (3.0, 1.5)), 1.0),)
    model = build(CFG, "warehouse", (-6, 0, 0), visuals=False, imu=False, actors=jack).model
    names = scan_plane_boxes(model, 0.15).names
    assert "pallet_0" in names  # a loose pallet is
    assert not any(n.startswith("pallet_jack") for n in names)
