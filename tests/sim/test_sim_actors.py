"""Actors in the running twin: they walk their paths on time (actors/poses and MuJoCo's bodies), the
LiDAR sees them where an independent ray cast puts them, the robot hitting one is a collision naming
it, a person told to wait for the robot does, and a seed gives the same trajectories."""

import math

import numpy as np
import pytest

from amr_twin.model.actor_paths import actor_path
from amr_twin.model.actor_space import random_actors
from amr_twin.model.actors import Actor
from amr_twin.model.world_spec import world_model
from amr_twin.model.config import load_config
from amr_twin.assembly.twin import Twin, TwinOptions

CFG = load_config()
P = CFG.actors.person
J = CFG.actors.pallet_jack
START = (-6.0, 0.0, 0.0)  # the warehouse's: robot front at x = -5.65, laser at x = -5.70


def _twin(actors, sensors=False, **kw):
    twin = Twin(
        CFG,
        TwinOptions(
            start_xy_yaw=START,
            sensors=("imu", "lidar") if sensors else (),
            actors=tuple(actors),
            visuals=False,
            **kw,
        ),
    )
    poses = []
    twin.bus.subscribe("actors/poses", poses.append, queue_size=1000)
    return twin, poses


def _xy_yaw(msg):
    return [(p.position.x, p.position.y, p.orientation.yaw_rad()) for p in msg.poses]


def test_an_actor_walks_its_waypoints_at_its_speed_on_the_bus_and_in_mujoco():
    """Down the aisle 5 m at 1.25 m/s from t = 1 s: where it is at known times, heading -y."""
    twin, poses = _twin([Actor("person", ((-4.0, 2.5), (-4.0, -2.5)), 1.25, start_s=1.0)])
    twin.advance(6.5)
    t = [m.header.stamp.to_sec() for m in poses]
    assert t == pytest.approx(np.arange(66) * 0.1) and {m.header.frame_id for m in poses} == {"map"}
    by_t = {round(m.header.stamp.to_sec(), 1): _xy_yaw(m)[0] for m in poses}
    for t_s, y in (
        (0.0, 2.5),
        (1.0, 2.5),
        (2.0, 1.25),
        (3.0, 0.0),
        (4.6, -2.0),
        (5.0, -2.5),
        (6.5, -2.5),
    ):
        x_m, y_m, yaw = by_t[t_s]
        assert (x_m, y_m) == pytest.approx((-4.0, y), abs=1e-9), t_s
        assert yaw == pytest.approx(-math.pi / 2, abs=1e-12)
    d = twin.physics.data
    body = twin.physics.model.body("person_0").id
    assert d.xpos[body][:2] == pytest.approx((-4.0, -2.5))  # MuJoCo's body went there too
    assert twin.actors.engine == "C"


def _leg_hits(origin, angle, legs, r):
    """Nearest distance along the ray from ``origin`` at ``angle`` to the circles ``legs`` (k, 2) of
    radius ``r`` (inf: none), and whether the ray grazes one (passes within 0.3 r of its edge: which
    leg it hits then depends on millimetres); a line-circle intersection in the plane, independent
    of MuJoCo."""
    u = np.array([math.cos(angle), math.sin(angle)])
    best, grazing = math.inf, False
    for c in legs:
        w = c - origin
        along = w @ u
        perp = abs(w[0] * u[1] - w[1] * u[0])
        if along <= 0:
            continue
        grazing |= abs(perp - r) < 0.3 * r
        if perp < r:
            best = min(best, along - math.sqrt(r * r - perp * perp))
    return best, grazing


def test_the_lidar_sees_a_person_crossing_where_an_independent_ray_cast_puts_them():
    """A walker crossing 2.2 m ahead at 1.2 m/s: each beam against the two leg circles at the beam's
    own instant. Where the cast says "leg", the scan's range agrees within 5 cm (noise and the 10-20
    ms the cast lags); where it says no leg, no return lies inside one (no ghost, no leg missed)."""
    person = Actor("person", ((-3.5, 1.6), (-3.5, -1.6)), 1.2, start_s=0.3)
    twin, _ = _twin([person], sensors=True)
    scans = []
    twin.bus.subscribe("scan", scans.append, queue_size=100)
    twin.advance(3.2)
    path, r = actor_path(person, CFG), P.leg_radius_m
    origin = twin.physics.site_position_m("amr/laser")[:2]  # the robot stands still
    yaw0 = twin.physics.pose().yaw_rad
    seen, checked = 0, 0
    for scan in scans:
        ranges = np.asarray(scan.ranges, float)
        for i, rng in enumerate(ranges):
            t_beam = scan.header.stamp.to_sec() + i * scan.time_increment
            x, y, yaw = path.pose_at(max(0.0, t_beam - person.start_s))
            legs = np.array(
                [
                    [
                        x - s * math.sin(yaw) * P.leg_spacing_m / 2,
                        y + s * math.cos(yaw) * P.leg_spacing_m / 2,
                    ]
                    for s in (1, -1)
                ]
            )
            angle = yaw0 + scan.angle_min + i * scan.angle_increment
            want, grazing = _leg_hits(origin, angle, legs, r)
            if grazing:
                continue
            if math.isfinite(want):
                checked += 1
                assert rng == pytest.approx(want, abs=0.05), (t_beam, i)
                seen += 1
            elif not math.isfinite(want) and math.isfinite(rng):
                end = origin + rng * np.array([math.cos(angle), math.sin(angle)])
                assert np.min(np.linalg.norm(legs - end, axis=1)) > r - 0.035, (t_beam, i)
    assert len(scans) >= 16 and checked == seen >= 20


@pytest.mark.parametrize("forks_first", [False, True])
def test_the_lidar_sees_a_jacks_pump_not_its_forks(forks_first):
    """A jack 2.2 m ahead, standing: its pump toward the robot is seen at the pump's face; turned
    round (forks toward the robot, 0.085 m high) the beam passes over the forks to the pump
    behind."""
    heading = (
        -1.0 if forks_first else 1.0
    )  # forks lead: its first segment's direction is where they point
    jack = Actor("pallet_jack", ((-3.5, 0.0), (-3.5 + heading, 0.0)), 1.0, start_s=1e5)
    twin, _ = _twin([jack], sensors=True)
    ranges = twin.sensors["lidar"].scan_now()
    ahead = twin.sensors["lidar"].n_beams // 2  # angle 0: straight ahead
    assert twin.sensors["lidar"].angles_rad[ahead] == pytest.approx(0.0, abs=1e-12)
    laser_x = twin.physics.site_position_m("amr/laser")[0]
    pump_centre = -3.5 - heading * (J.length_m / 2 - J.pump_radius_m)
    want = pump_centre - J.pump_radius_m - laser_x
    assert float(ranges[ahead]) == pytest.approx(want, abs=0.02)


def test_driving_into_a_person_is_a_collision_naming_them():
    twin, _ = _twin([Actor("person", ((-4.6, 0.0),), 1.0)])
    twin.client.linear(0.5)
    twin.advance(4.0)
    hits = twin.collisions.as_dicts()
    assert [h["hit"] for h in hits] == ["person_0"] and "base_link" in hits[0]["robot_parts"]
    assert 1.5 < hits[0]["t_s"] < 3.0 and hits[0]["x_m"] == pytest.approx(
        -4.6 - P.leg_radius_m, abs=0.02
    )


def test_a_wheel_or_caster_on_a_jacks_fork_is_a_collision():
    """Forks toward the robot, 0.085 m high: under the chassis (0.1 m), into the casters and
    wheels."""
    jack = Actor("pallet_jack", ((-4.5, 0.0), (-5.5, 0.0)), 1.0, start_s=1e5)
    twin, _ = _twin([jack])
    twin.client.linear(0.3)
    twin.advance(3.0)
    hits = twin.collisions.as_dicts()
    assert hits and hits[0]["hit"] == "pallet_jack_0"
    assert any(p.startswith(("caster", "wheel")) for p in hits[0]["robot_parts"])
    assert hits[0]["z_m"] < J.fork_height_m + 0.01


@pytest.mark.parametrize("stop_m", [0.0, 1.0])
def test_a_person_told_to_wait_stops_short_of_the_robot_and_one_not_told_walks_into_it(stop_m):
    person = Actor("person", ((-2.5, 0.0), (-8.0, 0.0)), 1.3, stop_within_m=stop_m)
    twin, poses = _twin([person])
    twin.advance(4.0)
    x_end = _xy_yaw(poses[-1])[0][0]
    front = START[0] + CFG.chassis.length_m / 2
    if stop_m:
        assert twin.collisions.as_dicts() == []
        assert (
            stop_m - 1.3 * 0.01 - 1e-9 <= x_end - front <= stop_m
        )  # it stops within one grid step of the line
        assert twin.actors.progress_s()[0] < 4.0 - 1.0  # it has been waiting
    else:
        assert [h["hit"] for h in twin.collisions.as_dicts()] == ["person_0"]


@pytest.mark.parametrize("side", [1.0, -1.0])
@pytest.mark.parametrize("angle_deg", [0.0, 40.0, 65.0, -65.0])
def test_a_person_giving_way_beside_the_robot_keeps_their_body_0_3_m_from_its_footprint(
    side, angle_deg
):
    """The navigation's acceptance asks 0.3 m from a person's body (the navigation metric's 0.30 x
    0.45 m box) to the robot's footprint (0.70 x 0.53 m: the wheels stick out of the 0.40 m
    chassis). A person walking at the robot's left or right side, square to it or at an angle
    (forwards or backwards; 65 deg is seed 0 episode 13's), waiting within 0.6 m: halted within one
    grid step of 0.6 m from their centre to the footprint across the wheels, their body at least 0.6
    - 0.27 - 0.013 m from it (shapely's distance, not the twin's). Measured to the chassis, they
    stood 0.065 m nearer, their body 0.275 m from the footprint at 65 deg."""
    from shapely.geometry import Polygon

    from amr_twin.experiments.navigation.metrics import PERSON_HALF_M
    from amr_twin.navigation.footprint import robot_footprint

    stop_m = 0.6
    fp = robot_footprint(CFG)
    heading = side * (math.radians(angle_deg) - math.pi / 2)  # towards the side, tilted
    target = np.array([START[0] + 0.1, START[1] + side * fp.half_width_m])
    u = np.array([math.cos(heading), math.sin(heading)])
    a, b = target - 2.0 * u, target + 0.5 * u
    twin, poses = _twin([Actor("person", (tuple(a), tuple(b)), 1.3, stop_within_m=stop_m)])
    twin.advance(3.0)
    ((x, y, yaw),) = _xy_yaw(poses[-1])
    assert twin.collisions.as_dicts() == [] and twin.actors.progress_s()[0] < 3.0 - 1.0  # it waited
    centre = np.array([x - START[0], y - START[1]])  # in base_link (the robot faces +x)
    assert stop_m - 1.3 * 0.01 - 1e-9 <= fp.distance_m(centre)[0] <= stop_m
    hx, hy = PERSON_HALF_M
    c, s = math.cos(yaw), math.sin(yaw)
    body = Polygon(
        [
            (x + c * px - s * py, y + s * px + c * py)
            for px, py in ((-hx, -hy), (hx, -hy), (hx, hy), (-hx, hy))
        ]
    )
    robot = Polygon([(START[0] + px, START[1] + py) for px, py in fp.corners_xy_m()])
    assert 0.3 <= body.distance(robot) <= stop_m - hx + 1e-9


def test_a_person_told_to_wait_walks_on_when_the_robot_is_behind():
    """Within 1 m of the robot but walking away from it: nothing in its way."""
    person = Actor("person", ((-5.0, 0.0), (-2.0, 0.0)), 1.0, stop_within_m=1.0)
    twin, poses = _twin([person])
    twin.advance(2.0)
    assert twin.actors.progress_s() == [2.0] and _xy_yaw(poses[-1])[0][0] == pytest.approx(-3.0)


def test_the_same_seed_gives_the_same_trajectories_and_another_seed_others():
    model = world_model(CFG, "warehouse")

    def run(seed):
        twin, poses = _twin(random_actors(model, 4, seed, CFG, START[:2]))
        twin.advance(2.0)
        return np.array([_xy_yaw(m) for m in poses])

    a, b = run(11), run(11)
    assert a.shape == (21, 4, 3) and np.array_equal(a, b)
    c = run(12)
    assert not np.allclose(a, c) and np.ptp(a[:, :, :2], axis=0).max() > 1.0  # they moved


def test_a_wheel_touching_an_actor_is_always_a_collision_even_standing_on_it():
    """A wheel on a rack's top face counts by the contact's normal (standing is not a collision); on
    an actor (a wheel up on a fork) it is one whatever the normal."""
    from amr_twin.sim.geom_roles import BY_NORMAL, COLLIDE, IGNORE, GeomRoles

    twin, _ = _twin([Actor("pallet_jack", ((0.0, 1.5), (3.0, 1.5)), 1.0)])
    m, roles = twin.physics.model, GeomRoles(twin.physics)
    wheel = twin.physics.support.geoms["wheel_left"]
    fork, rack, floor = (
        m.geom(n).id for n in ("pallet_jack_0/fork_left", "rack_n_beam_low", "floor")
    )
    assert roles.kind(wheel, fork) == COLLIDE and roles.kind(fork, wheel) == COLLIDE
    assert roles.kind(wheel, rack) == BY_NORMAL and roles.kind(wheel, floor) == IGNORE
    assert roles.world_name(fork) == "pallet_jack_0" and roles.world_name(rack) == "rack_n_beam_low"
