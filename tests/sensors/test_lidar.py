"""RPLIDAR A1: ranges in a known room, payload, motion distortion, own-geom masking, seeds,
services."""

import math
from types import SimpleNamespace

import mujoco
import numpy as np
import pytest

from amr_twin.model.build import build
from amr_twin.ros.bus import Bus
from amr_twin.base.clock import VirtualClock
from amr_twin.model.config import load_config
from amr_twin.sensors.lidar import Lidar

ROOM = (-2.0, 3.0, -1.5, 2.5)  # inner faces x_min, x_max, y_min, y_max, m
ROOM_XML = """<mujoco model="room"><worldbody>
  <geom name="floor" type="plane" size="10 10 0.1"/>
  <geom name="w_xmin" type="box" pos="-2.1 0.5 1" size="0.1 2.2 1"/>
  <geom name="w_xmax" type="box" pos="3.1 0.5 1" size="0.1 2.2 1"/>
  <geom name="w_ymin" type="box" pos="0.5 -1.6 1" size="2.7 0.1 1"/>
  <geom name="w_ymax" type="box" pos="0.5 2.6 1" size="2.7 0.1 1"/>
</worldbody></mujoco>"""
POSE = (0.4, 0.3, 0.5)  # base x, y, yaw


def room_ranges(p_xy, world_angle):
    """Analytic distance from p to the room's walls along each world angle, m."""
    c, s = np.cos(world_angle), np.sin(world_angle)
    x0, x1, y0, y1 = ROOM
    with np.errstate(divide="ignore"):
        tx = np.where(c > 0, (x1 - p_xy[0]) / c, (x0 - p_xy[0]) / c)
        ty = np.where(s > 0, (y1 - p_xy[1]) / s, (y0 - p_xy[1]) / s)
    return np.minimum(np.where(tx > 0, tx, np.inf), np.where(ty > 0, ty, np.inf))


@pytest.fixture(scope="module")
def room(tmp_path_factory):
    path = tmp_path_factory.mktemp("room") / "room.xml"
    path.write_text(ROOM_XML)
    return path


class Rig:
    """A compiled robot posed kinematically (no dynamics) with a LiDAR on its own clock."""

    def __init__(self, world, cfg=None, seed=0):
        self.cfg = cfg or load_config()
        self.m = build(self.cfg, world=world).model
        self.d = mujoco.MjData(self.m)
        self.adr = self.m.jnt_qposadr[self.m.joint("amr/root").id]
        self.dof = self.m.jnt_dofadr[self.m.joint("amr/root").id]
        self.clock = VirtualClock()
        self.bus = Bus(self.clock)
        self.scans = []
        self.bus.subscribe("scan", self.scans.append)
        self.lidar = Lidar(
            SimpleNamespace(model=self.m, data=self.d, prefix="amr/"),
            self.clock,
            self.bus,
            self.cfg.lidar,
            seed=seed,
            autostart=False,
        )

    def pose(self, x, y, yaw, yaw_rate=0.0):
        q = self.d.qpos
        q[self.adr : self.adr + 3] = [x, y, self.m.qpos0[self.adr + 2]]
        q[self.adr + 3 : self.adr + 7] = [math.cos(yaw / 2), 0, 0, math.sin(yaw / 2)]
        self.d.qvel[:] = 0
        self.d.qvel[self.dof + 5] = yaw_rate  # body-frame angular velocity about z
        mujoco.mj_forward(self.m, self.d)

    def run(self, t_end_us, yaw_rate=0.0):
        """Run the clock, posing the robot at every event (rotating about the base origin)."""
        while self.clock.next_event_us() <= t_end_us:
            t = self.clock.next_event_us()
            self.pose(POSE[0], POSE[1], POSE[2] + yaw_rate * t * 1e-6, yaw_rate)
            self.clock.run_until(t)

    def laser_offset(self):
        """Laser position in the base frame (xy), m."""
        self.pose(0.0, 0.0, 0.0)
        return self.d.site_xpos[self.lidar.site_id][:2].copy()


def sigma(cfg, r):
    return (
        np.maximum(cfg.lidar.range_noise_floor_m, cfg.lidar.range_noise_frac * r)
        + cfg.lidar.range_resolution_m
    )


def assert_matches(cfg, ranges, expected):
    z = np.abs(ranges - expected) / sigma(cfg, expected)
    assert np.all(np.isfinite(ranges))
    assert np.mean(z < 3) > 0.98 and z.max() < 5, (np.mean(z < 3), z.max())


def test_static_scan_matches_the_room(room):
    rig = Rig(room)
    off = rig.laser_offset()
    rig.lidar.start_motor()
    rig.run(rig.lidar.scan_us + 25_000)
    scan = rig.scans[0]
    lid = rig.lidar
    assert lid.n_beams == 364 and scan.header.frame_id == "laser"
    assert scan.angle_min == -math.pi and scan.angle_increment == pytest.approx(
        2 * math.pi / 364
    )  # CCW
    # the A1 spins clockwise: the last index first, beam 0 last; the stamp is beam 0's instant
    assert scan.header.stamp.to_us() == 363 * 500 and scan.time_increment == pytest.approx(-5e-4)
    assert scan.scan_time == pytest.approx(0.182)
    assert (scan.range_min, scan.range_max) == (0.15, 12.0)
    x, y, yaw = POSE
    p = (
        np.array([x, y])
        + np.array([[math.cos(yaw), -math.sin(yaw)], [math.sin(yaw), math.cos(yaw)]]) @ off
    )
    assert_matches(rig.cfg, scan.ranges, room_ranges(p, yaw + lid.angles_rad))
    assert np.array_equal(lid.last_beam_t_us, 500 * np.arange(363, -1, -1))
    from amr_twin.sensors.lidar_beams import beam_times_s

    assert np.allclose(
        beam_times_s(scan), lid.last_beam_t_us * 1e-6, atol=2e-8
    )  # float32 increment
    assert np.all(beam_times_s(scan) >= lid.last_beam_t_us * 1e-6)  # never before the true instant


def test_scan_while_turning_is_distorted_as_computed(room):
    omega = math.radians(60.0)
    static, moving = Rig(room), Rig(room)
    off = static.laser_offset()
    moving.laser_offset()
    for rig, w in ((static, 0.0), (moving, omega)):
        rig.lidar.start_motor()
        rig.run(rig.lidar.scan_us + 25_000, yaw_rate=w)
    lid = moving.lidar
    t_s = moving.lidar.last_beam_t_us * 1e-6
    yaw = POSE[2] + omega * t_s  # base yaw at each beam's own instant
    rot = np.stack([[np.cos(yaw), -np.sin(yaw)], [np.sin(yaw), np.cos(yaw)]])  # (2, 2, n)
    p = np.array(POSE[:2])[:, None] + np.einsum("ijn,j->in", rot, off)
    expected = np.array(
        [room_ranges(p[:, i], yaw[i] + lid.angles_rad[i]) for i in range(lid.n_beams)]
    )
    assert_matches(moving.cfg, moving.scans[0].ranges, expected)
    # the distortion is real: much larger than the noise on many beams, and as predicted
    rot0 = np.array(
        [[math.cos(POSE[2]), -math.sin(POSE[2])], [math.sin(POSE[2]), math.cos(POSE[2])]]
    )
    expected_static = room_ranges(np.array(POSE[:2]) + rot0 @ off, POSE[2] + lid.angles_rad)
    distortion = expected - expected_static
    big = np.abs(distortion) > 10 * sigma(moving.cfg, expected_static)
    assert big.sum() > 50
    measured = moving.scans[0].ranges - static.scans[0].ranges
    assert np.median(np.abs(measured[big] - distortion[big]) / np.abs(distortion[big])) < 0.1


def test_payload_in_the_scan_plane_is_seen(room):
    cfg = load_config(overrides={"payload.mass_kg": 20.0, "payload.xy_m": [-0.15, 0.0]})
    rig = Rig(room, cfg)
    rig.pose(*POSE)
    ranges = rig.lidar.scan_now()
    back = 0  # angle -pi: straight back over the deck; box front face at x = 0, laser at x = 0.30
    assert rig.m.geom(rig.lidar.hit_geom[back]).name == "amr/payload_box"
    off = rig.laser_offset()
    assert ranges[back] == pytest.approx(off[0], abs=3 * sigma(cfg, off[0]))


@pytest.mark.parametrize("world", ["room", "warehouse"])
def test_own_wheels_and_casters_never_seen(room, world):
    rig = Rig(room if world == "room" else world)
    for yaw in np.linspace(0, 2 * math.pi, 7):
        rig.pose(POSE[0], POSE[1], yaw)
        rig.lidar.scan_now()
        hit = rig.lidar.hit_geom[rig.lidar.hit_geom >= 0]
        assert len(hit) > 300
        assert np.all(rig.m.geom_bodyid[hit] == 0), [
            rig.m.geom(g).name for g in hit if rig.m.geom_bodyid[g]
        ]


def test_same_seed_same_scans_other_seed_different(room):
    out = []
    for seed in (7, 7, 8):
        rig = Rig(room, seed=seed)
        rig.lidar.start_motor()
        rig.run(2 * rig.lidar.scan_us + 25_000)
        out.append(np.concatenate([s.ranges for s in rig.scans]).tobytes())
    assert out[0] == out[1] and out[0] != out[2]


def test_motor_services_and_out_of_range(room):
    rig = Rig(room)
    rig.bus.call_service("start_motor", None)
    rig.run(400_000)
    lid = rig.lidar
    assert (
        len(rig.scans) == 2
        and rig.scans[1].header.stamp.to_us() == 2 * lid.scan_us - lid.beam_dt_us
    )
    rig.bus.call_service("stop_motor", None)
    rig.run(1_000_000)
    assert len(rig.scans) == 2
    r = rig.lidar.noisy_ranges(np.array([20.0, 0.05, 2.0, 5.0]), np.array([1, 1, -1, 1], np.int32))
    assert np.isinf(r[:3]).all() and r[3] == pytest.approx(5.0, abs=0.15)


def _run_on_grid(rig, t_end_us, yaw_rate, grid_us=10_000):
    """The twin's way: the loop samples the pose on its grid (no clock event); scans go out by
    publishing events."""
    samplers = []
    rig.lidar.start_motor(grid_us=grid_us, samplers=samplers)
    for t in range(0, t_end_us + 1, grid_us):
        rig.pose(POSE[0], POSE[1], POSE[2] + yaw_rate * t * 1e-6, yaw_rate)
        for sampler in samplers:
            sampler(t)
        rig.clock.run_until(t)


@pytest.mark.parametrize("speed_m_s, seed", [(0.0, 0)] + [(0.7, seed) for seed in range(20)])
def test_twin_mode_scan_while_turning_and_driving_is_distorted_as_computed(room, speed_m_s, seed):
    """One cast per rotation (the twin's default): beam directions and origins at their own
    instants. Driving, on 20 seeds of the range noise (it once held on seed 0 only)."""
    omega = math.radians(60.0)
    rig = Rig(room, seed=seed)
    off = rig.laser_offset()
    base_pose = rig.pose

    def moving_pose(x, y, yaw, yaw_rate=0.0):  # drive along x while turning
        t_s = (yaw - POSE[2]) / omega
        base_pose(x + speed_m_s * t_s, y, yaw, yaw_rate)
        rig.d.qvel[rig.dof] = speed_m_s

    rig.pose = moving_pose
    _run_on_grid(rig, rig.lidar.scan_us + 20_000, omega)
    lid = rig.lidar
    assert lid.cast_every_us >= lid.scan_us and len(rig.scans) == 1
    assert np.array_equal(lid.last_beam_t_us, 500 * np.arange(363, -1, -1))  # clockwise, as the A1
    assert rig.scans[0].header.stamp.to_us() == lid.last_beam_t_us[0] == 181_500
    t_s = lid.last_beam_t_us * 1e-6
    yaw = POSE[2] + omega * t_s
    rot = np.stack([[np.cos(yaw), -np.sin(yaw)], [np.sin(yaw), np.cos(yaw)]])
    p = (
        np.array(POSE[:2])[:, None]
        + np.array([speed_m_s, 0.0])[:, None] * t_s
        + np.einsum("ijn,j->in", rot, off)
    )
    expected = np.array(
        [room_ranges(p[:, i], yaw[i] + lid.angles_rad[i]) for i in range(lid.n_beams)]
    )
    assert_matches(
        rig.cfg, rig.scans[0].ranges, expected
    )  # each beam from its own origin, corners too


def test_twin_mode_payload_moves_with_the_laser(room):
    cfg = load_config(overrides={"payload.mass_kg": 20.0, "payload.xy_m": [-0.15, 0.0]})
    rig = Rig(room, cfg)
    off = rig.laser_offset()
    _run_on_grid(rig, rig.lidar.scan_us + 20_000, math.radians(90.0))
    assert rig.m.geom(rig.lidar.last_hit_geom[0]).name == "amr/payload_box"
    assert rig.scans[0].ranges[0] == pytest.approx(off[0], abs=3 * sigma(cfg, off[0]))


# Thin things at the laser's height (0.45 m): uprights 0.1 m and 0.04 m wide, braces 0.04 m thick
# at z 0.40-0.50 m between them (as the aisles world's racks), a round post, three walls (open at
# -y).
THIN_XML = """<mujoco model="thin"><worldbody>
  <geom name="floor" type="plane" size="20 20 0.1"/>
  {uprights}
  <geom name="post" type="cylinder" pos="1.6 0.9 0.6" size="0.03 0.6"/>
  <geom name="brace_a" type="box" pos="1.0 -0.9 0.45" size="0.9 0.02 0.05"/>
  <geom name="brace_b" type="box" pos="2.6 0.55 0.45" size="0.02 0.45 0.05" euler="0 0 0.3"/>
  <geom name="wall_x" type="box" pos="6.0 0.0 1.0" size="0.1 3.0 1.0"/>
  <geom name="wall_y" type="box" pos="1.0 3.0 1.0" size="5.1 0.1 1.0"/>
  <geom name="wall_back" type="box" pos="-4.0 0.0 1.0" size="0.1 3.0 1.0"/>
</worldbody></mujoco>"""


@pytest.fixture(scope="module")
def thin(tmp_path_factory):
    uprights = [
        (0.1 + 0.45 * i, -0.9 + (0.0 if i % 2 else 0.02), 0.05 if i % 2 else 0.02) for i in range(5)
    ]
    uprights += [(0.6 + 0.5 * i, 0.75, 0.05 if i % 2 else 0.02) for i in range(4)]
    xml = THIN_XML.format(
        uprights="\n  ".join(
            f'<geom name="upright_{k}" type="box" pos="{x:.3f} {y:.3f} 0.6" size="{h} {h} 0.6"/>'
            for k, (x, y, h) in enumerate(uprights)
        )
    )
    path = tmp_path_factory.mktemp("thin") / "thin.xml"
    path.write_text(xml)
    return path


@pytest.mark.parametrize(
    "speed_m_s, omega_rad_s, seed", [(0.8, 0.6, 0), (0.5, -0.4, 1), (0.8, 1.2, 2)]
)
def test_every_return_is_what_a_ray_from_its_own_laser_pose_hits(
    thin, speed_m_s, omega_rad_s, seed
):
    """Driving and turning past thin uprights, braces and a post: each return is within the range
    noise of MuJoCo's own ``mj_ray`` cast from the laser pose at that beam's instant (linear between
    the pose samples every 20 ms, interpolated here with ``numpy.interp``) where that ray hits
    within the range limits, and no return where it hits nothing: no return off every surface (the
    ghosts of the old plane correction near thin and finite objects, 0.1-0.9 m off any geom)."""
    rig = Rig(thin, seed=seed)
    start = (-0.6, -0.05, 0.1)
    samples = {}  # t_us -> laser origin (3,), x axis (3,), y axis (3,)

    def pose_at(t_us):
        t_s = t_us * 1e-6
        yaw = start[2] + omega_rad_s * t_s
        # a constant-curvature arc at speed_m_s and omega_rad_s (kinematic: the base's origin)
        x = start[0] + speed_m_s * (math.sin(yaw) - math.sin(start[2])) / omega_rad_s
        y = start[1] - speed_m_s * (math.cos(yaw) - math.cos(start[2])) / omega_rad_s
        Rig.pose(rig, x, y, yaw, omega_rad_s)
        s = rig.lidar.site_id
        samples[t_us] = np.concatenate(
            [
                rig.d.site_xpos[s],
                rig.d.site_xmat[s].reshape(3, 3)[:, 0],
                rig.d.site_xmat[s].reshape(3, 3)[:, 1],
            ]
        )

    grid_us, t_end_us = 10_000, 5 * rig.lidar.scan_us + 20_000
    samplers = []
    rig.lidar.start_motor(grid_us=grid_us, samplers=samplers)
    stamps = []
    rig.bus.subscribe("scan", lambda msg: stamps.append(rig.lidar.last_beam_t_us.copy()))
    for t in range(0, t_end_us + 1, grid_us):
        pose_at(t)
        for sampler in samplers:
            sampler(t)
        rig.clock.run_until(t)
    assert len(rig.scans) == 5
    period = rig.lidar.cast_period_us
    ts = np.array([t for t in sorted(samples) if t % period == 0], float)
    table = np.array([samples[int(t)] for t in ts])
    cfg, lid = rig.cfg.lidar, rig.lidar
    groups = np.array([1, 0, 0, 0, 0, 0], np.uint8)  # the world's geoms (group 0) only
    gid, nrm = np.zeros(1, np.int32), np.zeros(3)
    hits = thin_hits = 0
    for scan, beam_t in zip(rig.scans, stamps):
        for i, t_us in enumerate(beam_t):
            p = np.array([np.interp(t_us, ts, table[:, c]) for c in range(9)])
            u = p[3:6] * lid.local_dirs[i, 0] + p[6:9] * lid.local_dirs[i, 1]
            u /= np.linalg.norm(u)
            ref = mujoco.mj_ray(rig.m, rig.d, p[:3], u, groups, 1, -1, gid, nrm)
            r = float(scan.ranges[i])
            if gid[0] < 0 or not cfg.range_min_m + 0.01 < ref < cfg.range_max_m - 0.01:
                assert not np.isfinite(r) or gid[0] >= 0, (i, r, ref)
                continue
            tol = (
                5 * max(cfg.range_noise_floor_m, cfg.range_noise_frac * ref)
                + cfg.range_resolution_m
                + 0.002
            )
            assert abs(r - ref) <= tol, (i, t_us, r, ref, rig.m.geom(gid[0]).name)
            hits += 1
            thin_hits += rig.m.geom(gid[0]).name.startswith(("upright", "brace", "post"))
    assert hits > 1000 and thin_hits > 200
