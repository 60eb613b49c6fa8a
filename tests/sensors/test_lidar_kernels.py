"""The LiDAR's per-beam arithmetic: the C helper against its numpy twin, to the bit."""

import shutil

import numpy as np
import pytest

from amr_twin.model.config import load_config
from amr_twin.sensors.lidar_beams import PoseSamples
from amr_twin.sensors.lidar_kernels import beam_kernels

pytestmark = pytest.mark.skipif(shutil.which("cc") is None and shutil.which("gcc") is None, reason="no C compiler")
CFG = load_config().lidar


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
    poses = PoseSamples()
    for i in range(n):
        yaw, tilt = rng.uniform(-np.pi, np.pi), rng.normal(0.0, 0.02)
        c, s = np.cos(yaw), np.sin(yaw)
        xmat = np.array([[c, -s, tilt], [s, c, 0.0], [-tilt, 0.0, 1.0]]).ravel()
        poses.append(20_000 * i, rng.normal(0.0, 2.0, 3), xmat)
    return poses


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_directions_and_shifts_are_the_same_bits(seed):
    c, py = _kernels()
    rng = np.random.default_rng(seed)
    for n in (1, 2, 5, 11):  # one sample (held), and instants before, between and after the samples
        poses = _poses(rng, n)
        t_us, lx, ly = _rotation(rng, int(rng.integers(1, 365)))
        origin = rng.normal(0.0, 2.0, 3)
        u_c, shift_c = (a.copy() for a in c.geometry(t_us, lx, ly, poses.rows, poses.n, origin))
        u_py, shift_py = py.geometry(t_us, lx, ly, poses.rows, poses.n, origin)
        assert u_c.tobytes() == u_py.tobytes() and shift_c.tobytes() == shift_py.tobytes()
        assert np.allclose(np.linalg.norm(u_c, axis=1), 1.0)


@pytest.mark.parametrize("seed", [0, 1])
def test_motion_correction_and_noise_are_the_same_bits(seed):
    c, py = _kernels()
    rng = np.random.default_rng(seed)
    k = 364
    normal = rng.normal(0.0, 1.0, (k, 3))
    normal[::7] = 0.0  # no hit
    u = rng.normal(0.0, 1.0, (k, 3))
    u /= np.linalg.norm(u, axis=1)[:, None]
    u[::11] = np.cross(normal[::11], [0.0, 0.0, 1.0]) + 1e-5  # grazing
    shift = rng.normal(0.0, 0.05, (k, 3))
    dist = rng.uniform(-1.0, 14.0, k)
    d_c, d_py = dist.copy(), dist.copy()
    c.correct(normal, u, shift, d_c)
    py.correct(normal, u, shift, d_py)
    assert d_c.tobytes() == d_py.tobytes() and not np.array_equal(d_c, dist)
    geomid = rng.integers(-1, 5, k).astype(np.int32)
    z = rng.standard_normal(k)
    r_c, r_py = c.noise(d_c, geomid, z), py.noise(d_py, geomid, z)
    assert r_c.dtype == r_py.dtype == np.float32 and r_c.tobytes() == r_py.tobytes()
    assert np.isinf(r_c).any() and np.isfinite(r_c).any()


def test_a_twins_scans_are_the_same_bits_with_and_without_the_helper(monkeypatch):
    """Driving and spinning with a payload in the scan plane: every scan identical (C cast, numpy twin)."""
    import functools

    import amr_twin.sensors.lidar as lidar_mod
    from amr_twin.sim.loop import Twin, TwinOptions

    cfg = load_config(overrides={"payload.mass_kg": 20.0, "payload.xy_m": [-0.15, 0.0]})  # seen from the laser
    out = []
    for native in (True, False):
        monkeypatch.setattr(lidar_mod, "Lidar", functools.partial(lidar_mod.Lidar, native=native))
        twin = Twin(cfg, TwinOptions(sensors=True))
        scans = []
        twin.bus.subscribe("scan", lambda msg: scans.append(msg.ranges.tobytes()))
        twin.client.linear(0.7)
        twin.advance(1.5)
        twin.client.angular(-60.0, 0.0)
        twin.advance(1.5)
        out.append((twin.lidar.engine, scans, twin.lidar.dist_m.tobytes()))
    (c_engine, *c_scans), (py_engine, *py_scans) = out
    assert c_engine == "C" and py_engine == "Python (native=False)"
    assert len(c_scans[0]) >= 15 and c_scans == py_scans
