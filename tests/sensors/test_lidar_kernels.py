"""The LiDAR's per-beam arithmetic: the C helper against its numpy twin, to the bit."""

import math
import shutil
from types import SimpleNamespace

import numpy as np
import pytest

from amr_twin.model.config import load_config
from amr_twin.sensors.lidar_kernels import beam_kernels

pytestmark = pytest.mark.skipif(
    shutil.which("cc") is None and shutil.which("gcc") is None, reason="no C compiler"
)
CFG = load_config().lidar
WORLD_ONLY = np.array([1, 0, 0, 0, 0, 0], np.uint8)
"""Geom groups the test casts see: the world (group 0) alone."""


def _kernels():
    c, py = beam_kernels(364, CFG), beam_kernels(364, CFG, native=False)
    assert c.engine == "C" and py.engine == "Python (native=False)"
    return c, py


def _rotation(rng, k):
    """k beams' instants (descending, as a rotation is acquired) and laser-frame components."""
    t_us = 180_000 - 500 * np.arange(k, dtype=np.int64) + int(rng.integers(-40_000, 40_000))
    angles = rng.uniform(-np.pi, np.pi, k)
    return t_us, np.cos(angles)[:, None].copy(), np.sin(angles)[:, None].copy()


def _poses(rng, n):
    """n pose samples as PoseSamples keeps them: rows of t_us, position, the laser x axis and y axis
    (the first and second columns of the site's rotation)."""
    rows = []
    for i in range(n):
        yaw, tilt = rng.uniform(-np.pi, np.pi), rng.normal(0.0, 0.02)
        c, s = np.cos(yaw), np.sin(yaw)
        xmat = np.array([[c, -s, tilt], [s, c, 0.0], [-tilt, 0.0, 1.0]])
        rows.append([20_000 * i, *rng.normal(0.0, 2.0, 3), *xmat[:, 0], *xmat[:, 1]])
    return SimpleNamespace(rows=np.array(rows), n=n)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_directions_and_origins_are_the_same_bits(seed):
    c, py = _kernels()
    rng = np.random.default_rng(seed)
    for n in (1, 2, 5, 11):  # one sample (held), and instants before, between and after the samples
        poses = _poses(rng, n)
        t_us, lx, ly = _rotation(rng, int(rng.integers(1, 365)))
        u_c, org_c = (a.copy() for a in c.geometry(t_us, lx, ly, poses.rows, poses.n))
        u_py, org_py = py.geometry(t_us, lx, ly, poses.rows, poses.n)
        assert u_c.tobytes() == u_py.tobytes() and org_c.tobytes() == org_py.tobytes()
        assert np.allclose(np.linalg.norm(u_c, axis=1), 1.0)
        # each origin lies on the segment between the samples around its instant (held outside them)
        ts = poses.rows[: poses.n, 0]
        for i in range(0, len(t_us), 17):
            ref = [np.interp(t_us[i], ts, poses.rows[: poses.n, 1 + a]) for a in range(3)]
            assert np.allclose(org_c[i], ref, rtol=0, atol=1e-12)


@pytest.mark.parametrize("seed", [0, 1])
def test_noise_is_the_same_bits(seed):
    c, py = _kernels()
    rng = np.random.default_rng(seed)
    k = 364
    d_c = d_py = rng.uniform(-1.0, 14.0, k)
    geomid = rng.integers(-1, 5, k).astype(np.int32)
    z = rng.standard_normal(k)
    r_c, r_py = c.noise(d_c, geomid, z), py.noise(d_py, geomid, z)
    assert r_c.dtype == r_py.dtype == np.float32 and r_c.tobytes() == r_py.tobytes()
    assert np.isinf(r_c).any() and np.isfinite(r_c).any()


def test_a_twins_scans_are_the_same_bits_with_and_without_the_helper(monkeypatch):
    """Driving and spinning with a payload in the scan plane: every scan identical (C cast, numpy
    twin)."""
    import functools

    import amr_twin.sensors.lidar as lidar_mod
    from amr_twin.assembly.twin import Twin, TwinOptions

    cfg = load_config(
        overrides={"payload.mass_kg": 20.0, "payload.xy_m": [-0.15, 0.0]}
    )  # seen from the laser
    out = []
    for native in (True, False):
        monkeypatch.setattr(lidar_mod, "Lidar", functools.partial(lidar_mod.Lidar, native=native))
        twin = Twin(cfg, TwinOptions(sensors=("imu", "lidar")))
        scans = []
        twin.bus.subscribe("scan", lambda msg: scans.append(msg.ranges.tobytes()))
        twin.client.linear(0.7)
        twin.advance(1.5)
        twin.client.angular(-60.0, 0.0)
        twin.advance(1.5)
        out.append((twin.sensors["lidar"].engine, scans, twin.sensors["lidar"].dist_m.tobytes()))
    (c_engine, *c_scans), (py_engine, *py_scans) = out
    assert c_engine == "C" and py_engine == "Python (native=False)"
    assert len(c_scans[0]) >= 15 and c_scans == py_scans


def _laser_scene(geoms: str):
    """A model of ``geoms`` and a mocap ``laser`` site 0.5 m up at the origin, forwarded: (MjModel,
    MjData)."""
    import mujoco

    m = mujoco.MjModel.from_xml_string(f"""<mujoco><worldbody>{geoms}
      <body name="laser" mocap="true" pos="0 0 0.5"><site name="laser"/></body>
      </worldbody></mujoco>""")
    d = mujoco.MjData(m)
    mujoco.mj_forward(m, d)
    return m, d


def _scene(rng, mesh: bool = False) -> str:
    """A random MJCF world: primitives of every kind turned any way, some unseen (group 3), some
    invisible, some doubled, a panel flush with a wall, one on a free body, a floor; a mesh box with
    ``mesh``."""
    kinds = [
        ("box", "0.4 0.2 0.6"),
        ("cylinder", "0.3 0.5"),
        ("capsule", "0.2 0.4"),
        ("sphere", "0.35"),
        ("ellipsoid", "0.5 0.2 0.3"),
        ("box", "3.0 0.05 1.0"),
    ]
    # a panel flush with the face of a long wall, listed first: rays hit both at the same distance,
    # the wall's bounding sphere is nearer, and the panel (the lower id) must win, as in mj_multiRay
    geoms = [
        '<geom type="box" size="0.2 1.0 1.0" pos="3.0 0.0 0.5"/>',
        '<geom type="box" size="0.2 5.0 2.0" pos="3.0 0.0 0.5"/>',
    ]
    for i in range(40):
        kind, size = kinds[i % len(kinds)]
        pos = " ".join(f"{v:.3f}" for v in rng.uniform([-6, -6, -0.5], [6, 6, 2.0]))
        euler = " ".join(f"{v:.3f}" for v in rng.uniform(-3.1, 3.1, 3))
        extra = ' group="3"' if i % 9 == 4 else (' rgba="1 1 1 0"' if i % 11 == 6 else "")
        geoms.append(f'<geom type="{kind}" size="{size}" pos="{pos}" euler="{euler}"{extra}/>')
        if i % 10 == 0:  # a twin in the same place: equal distances, the lower id wins
            geoms.append(geoms[-1])
    if mesh:
        geoms.append('<geom type="mesh" mesh="cube" pos="2 2 0.5"/>')
    assets = (
        '<asset><mesh name="cube" vertex="0 0 0 1 0 0 0 1 0 1 1 0 0 0 1 1 0 1 0 1 1 1 1 '
        '1"/></asset>'
        if mesh
        else ""
    )
    return f"""<mujoco>{assets}<worldbody><geom type="plane" size="0 0 1"/>{"".join(geoms)}
      <body name="crate" pos="1.5 -1 0.4"><freejoint/><geom type="box" size="0.3 0.3 0.3"/></body>
      <body name="laser" mocap="true"><site name="laser"/></body></worldbody></mujoco>"""


@pytest.mark.parametrize("seed", [0, 1, 2])
@pytest.mark.parametrize("mesh", [False, True])
def test_the_culled_cast_hits_what_mj_multiray_and_mj_ray_hit(seed, mesh):
    """lb_cast's own cull in front of mju_rayGeom against MuJoCo's mj_multiRay and a mj_ray per
    beam: the same geom, distance and normal to the bit, from origins inside and outside the geoms'
    outlines, along directions tilted up to 60 degrees (a mesh in view: mj_multiRay casts)."""
    import mujoco

    c = beam_kernels(500, CFG)
    rng = np.random.default_rng(seed)
    m = mujoco.MjModel.from_xml_string(_scene(rng, mesh))
    d = mujoco.MjData(m)
    groups = WORLD_ONLY
    site = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_SITE, "laser")
    c.bind(m, d, site, groups)
    hits = 0
    for _ in range(12):
        d.mocap_pos[0] = rng.uniform([-6, -6, 0.05], [6, 6, 1.5])
        mujoco.mj_forward(m, d)
        origin = d.site_xpos[site].copy()
        az, tilt = rng.uniform(-np.pi, np.pi, 500), rng.uniform(-1.05, 1.05, 500)
        u = np.stack([np.cos(az) * np.cos(tilt), np.sin(az) * np.cos(tilt), np.sin(tilt)], axis=1)
        dist, geomid = np.zeros(500), np.zeros(500, np.int32)
        normal = c.rays(origin, u, dist, geomid).copy()
        ref_d, ref_g, ref_n = np.zeros(500), np.zeros(500, np.int32), np.zeros(1500)
        mujoco.mj_multiRay(m, d, origin, u.ravel(), groups, 1, -1, ref_g, ref_d, ref_n, 500, 1e6)
        assert geomid.tobytes() == ref_g.tobytes() and dist.tobytes() == ref_d.tobytes()
        assert normal.ravel().tobytes() == ref_n.tobytes()
        for i in range(0, 500, 7):
            gid, nrm = np.zeros(1, np.int32), np.zeros(3)
            x = mujoco.mj_ray(m, d, origin, u[i], groups, 1, -1, gid, nrm)
            assert (x, int(gid[0])) == (dist[i], geomid[i]) and nrm.tobytes() == normal[i].tobytes()
        hits += int((geomid >= 0).sum())
    assert hits > 1000


@pytest.mark.parametrize("seed", [0, 1, 2])
@pytest.mark.parametrize("mesh", [False, True])
def test_each_beam_is_cast_from_its_own_origin(seed, mesh):
    """lb_cast with the laser moving up to 0.6 m during the beams (its cull prepared once from the
    present origin, each geom's span widened for the beam's own origin) and the numpy twin: for
    every beam, the geom and distance of MuJoCo's ``mj_ray`` from that beam's own origin along its
    own direction, to the bit (a mesh in view: mj_multiRay per beam)."""
    import mujoco

    c, py = _kernels()
    rng = np.random.default_rng(10 + seed)
    m = mujoco.MjModel.from_xml_string(_scene(rng, mesh))
    d = mujoco.MjData(m)
    groups = WORLD_ONLY
    site = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_SITE, "laser")
    c.bind(m, d, site, groups)
    py.bind(m, d, site, groups)
    hits = moved = 0
    for _ in range(8):
        end = rng.uniform([-5, -5, 0.1], [5, 5, 1.2])
        d.mocap_pos[0] = end
        mujoco.mj_forward(m, d)
        poses = _poses(rng, 10)  # 10 samples 20 ms apart ending at the present origin
        poses.rows[:, 1:4] = (
            end + np.cumsum(rng.normal(0.0, 0.12, (10, 3)) * [1, 1, 0.05], axis=0)[::-1]
        )
        poses.rows[:, 1:4] -= poses.rows[-1, 1:4] - end
        t_us, lx, ly = _rotation(rng, 364)
        out = []
        for k in (c, py):
            dist, geomid = np.zeros(364), np.zeros(364, np.int32)
            k.cast(t_us, lx, ly, poses.rows, poses.n, dist, geomid)
            out.append((dist, geomid))
        (d_c, g_c), (d_py, g_py) = out
        assert d_c.tobytes() == d_py.tobytes() and g_c.tobytes() == g_py.tobytes()
        u, origin = py.geometry(t_us, lx, ly, poses.rows, poses.n)
        for i in range(364):
            gid, nrm = np.zeros(1, np.int32), np.zeros(3)
            x = mujoco.mj_ray(m, d, origin[i], u[i], groups, 1, -1, gid, nrm)
            assert (x, int(gid[0])) == (d_c[i], g_c[i]), i
        hits += int((g_c >= 0).sum())
        moved += int((np.linalg.norm(origin - end, axis=1) > 0.15).sum())
    assert hits > 1500 and moved > 1000


def test_a_beam_from_an_origin_nearer_a_small_geom_sees_it():
    """The laser drove 0.5 m away from a small sphere during the rotation: a beam acquired then,
    cast from there, hits the sphere at 1.4 m, not the wall behind it at 1.8 m, though the sphere's
    bounding sphere is 1.9 m from the present origin, farther than that wall hit (the cull's early
    stop is loosened by how far each beam's origin is from the present one)."""
    c, py = _kernels()
    m, d = _laser_scene("""
      <geom name="ball" type="sphere" size="0.1" pos="2.0 0 0.5"/>
      <geom name="wall" type="box" size="0.1 4.0 1.0" pos="2.4 0 1.0"/>""")
    groups = WORLD_ONLY
    rows = np.array(
        [[0.0, 0.5, 0.0, 0.5, 1, 0, 0, 0, 1, 0], [20_000.0, 0.0, 0.0, 0.5, 1, 0, 0, 0, 1, 0]]
    )
    t_us, lx, ly = np.array([0, 20_000], np.int64), np.ones((2, 1)), np.zeros((2, 1))
    for k in (c, py):
        k.bind(m, d, 0, groups)
        dist, geomid = np.zeros(2), np.zeros(2, np.int32)
        k.cast(t_us, lx, ly, rows, 2, dist, geomid)
        assert [m.geom(g).name for g in geomid] == ["ball", "ball"]
        assert dist == pytest.approx([1.4, 1.9], abs=1e-12)


def test_a_beam_from_beside_a_thin_post_sees_it():
    """An 8 mm post 10 cm ahead of the present origin; a beam acquired 10 cm away, 3.5 cm from the
    post, aimed at it 80 degrees off the post's azimuth seen from the present origin, hits it (an
    origin as far off as the post's nearest corner: the post is tried by every such beam, no span
    widened)."""
    c, py = _kernels()
    m, d = _laser_scene("""
      <geom name="post" type="cylinder" size="0.004 0.6" pos="0.1 0 0.6"/>
      <geom name="wall" type="box" size="4.0 0.1 1.0" pos="0 -3.0 1.0"/>""")
    groups = WORLD_ONLY
    o = 0.1 * np.array([np.cos(0.35), np.sin(0.35)])
    to_post = np.array([0.1, 0.0]) - o
    az = math.atan2(to_post[1], to_post[0])
    rows = np.array([[0.0, *o, 0.5, 1, 0, 0, 0, 1, 0], [20_000.0, 0.0, 0.0, 0.5, 1, 0, 0, 0, 1, 0]])
    t_us, lx, ly = (
        np.array([0], np.int64),
        np.full((1, 1), math.cos(az)),
        np.full((1, 1), math.sin(az)),
    )
    assert (
        az < -1.38
    )  # outside the post's span seen from the present origin, widened by x (1 + x^2 / 4)
    for k in (c, py):
        k.bind(m, d, 0, groups)
        dist, geomid = np.zeros(1), np.zeros(1, np.int32)
        k.cast(t_us, lx, ly, rows, 2, dist, geomid)
        assert m.geom(int(geomid[0])).name == "post"
        assert dist[0] == pytest.approx(np.linalg.norm(to_post) - 0.004, abs=1e-9)
