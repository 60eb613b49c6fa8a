"""MPPI's C helper (amr_twin/navigation/mppi_critics.c) against its NumPy twin (``native=False``):
the same samples and rollouts bit for bit, the same costs to float32 rounding (the same bits here),
the same collisions and the same commands cycle after cycle, on random rollouts in a room with racks
and people about."""

import math

import numpy as np
import pytest

from amr_twin.navigation.costmap import Costmap
from amr_twin.navigation.footprint import Footprint
from amr_twin.navigation.kinematics import Limits
from amr_twin.navigation.mppi import Mppi
from amr_twin.navigation.path_handler import PathHandler
from amr_twin.navigation.people import People

from nav_grids import room

FP = Footprint(-0.35, 0.35, 0.265)
RACKS = [(3.0, 2.0, 9.0, 2.8), (3.0, 5.2, 9.0, 6.0), (5.5, 3.6, 6.0, 4.1)]


@pytest.fixture(scope="module")
def costmap():
    return Costmap(room(walls=RACKS), 0.265, 1.0, 3.0)


def _pair(costmap, **kw):
    fast, slow = (
        Mppi(costmap, FP, Limits(), 0.05, seed=3, **kw),
        Mppi(costmap, FP, Limits(), 0.05, seed=3, native=False, **kw),
    )
    if fast.engine != "C":
        pytest.skip(f"the C critics are not built here: {fast.engine}")
    return fast, slow


def _path(start, goal, n=200):
    xy = np.linspace(start, goal, n)
    yaw = math.atan2(goal[1] - start[1], goal[0] - start[0])
    return PathHandler(np.column_stack([xy, np.full(n, yaw)]))


def _case(rng):
    """A random pose in the aisle, random controls around a random nominal, a path, people (or
    none)."""
    pose = np.array([rng.uniform(1.0, 11.0), rng.uniform(3.0, 5.0), rng.uniform(-math.pi, math.pi)])
    goal = np.array([rng.uniform(1.0, 11.0), rng.uniform(3.0, 5.0)])
    if rng.random() < 0.3:  # near the goal: the goal critic instead of the path's
        goal = pose[:2] + rng.uniform(-0.4, 0.4, 2)
    n = int(rng.integers(0, 5))
    people = People(
        float(rng.uniform(0, 5)),
        pose[:2] + rng.uniform(-3.0, 3.0, (n, 2)),
        rng.uniform(-1.2, 1.2, (n, 2)),
    )
    return (
        pose,
        (float(rng.uniform(-0.2, 1.0)), float(rng.uniform(-1, 1))),
        _path(pose[:2], goal),
        people,
    )


def test_the_c_critics_give_the_numpy_costs_collisions_and_commands_on_random_rollouts(costmap):
    fast, slow = _pair(costmap)
    rng, hits, crowded = np.random.default_rng(11), 0, 0
    for _ in range(30):
        pose, vel, path, people = _case(rng)
        u = fast.rng.standard_normal((fast.T, fast.K, 2), dtype=np.float32) * np.float32(
            0.6
        ) + np.float32(rng.uniform(-0.3, 1.0))
        u_fast = u_slow = slow._feasible(u, *vel)
        x, y, yaw = fast.rollout(pose, u_fast)
        for a, b in zip((x, y, yaw), slow.rollout(pose, u_slow)):
            assert np.array_equal(a, b)  # the rollout: the same bits
        t_s = people.t_s + float(rng.uniform(0.0, 0.3))
        c_fast, h_fast = fast.costs(x, y, yaw, u_fast, path, people, t_s)
        c_slow, h_slow = slow.costs(x, y, yaw, u_slow, path, people, t_s)
        assert np.array_equal(h_fast, h_slow)
        np.testing.assert_allclose(c_fast, c_slow, rtol=2e-6, atol=1e-5)
        assert np.argmin(c_fast) == np.argmin(c_slow)
        hits += h_slow.any() and not h_slow.all()
        crowded += bool(len(people)) and bool(np.ptp(c_slow) > 0)
    assert hits >= 3 and crowded >= 10  # the cases did reach walls and people


def test_the_c_and_numpy_controllers_give_the_same_commands_cycle_after_cycle(costmap):
    fast, slow = _pair(costmap)
    rng = np.random.default_rng(5)
    for _ in range(6):
        pose, vel, path, people = _case(rng)
        for k in range(8):  # the nominal carries over: the same commands, cycle after cycle
            a = fast.command(pose, vel, path, people, people.t_s + 0.05 * k)
            b = slow.command(pose, vel, path, people, people.t_s + 0.05 * k)
            assert (
                abs(a.v_m_s - b.v_m_s) < 1e-4
                and abs(a.w_rad_s - b.w_rad_s) < 1e-4
                and a.blocked == b.blocked
            )
            vel = (a.v_m_s, a.w_rad_s)
            pose = pose + 0.05 * np.array(
                [vel[0] * math.cos(pose[2]), vel[0] * math.sin(pose[2]), vel[1]]
            )


def test_the_c_and_numpy_samples_are_the_same_bits(costmap):
    """The sampled control sequences of a cycle (noise scaled about the nominal, clipped to the
    ramps)."""
    fast, slow = _pair(costmap)
    rng = np.random.default_rng(8)
    for _ in range(5):
        nominal = np.column_stack([rng.uniform(-0.2, 1.0, fast.T), rng.uniform(-1.5, 1.5, fast.T)])
        fast.nominal[:], slow.nominal[:] = nominal, nominal
        vel = (float(rng.uniform(-0.2, 1.0)), float(rng.uniform(-1.5, 1.5)))
        a, b = fast._sample(*vel), slow._sample(*vel)
        assert np.array_equal(
            a, b
        )  # noise about the nominal, the nominal and braking samples, the ramps
        assert (
            np.ptp(a[-1, 2:, 0]) > 0.1
        )  # the samples do spread (the first step is pinned by the ramps)
