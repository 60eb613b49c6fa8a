"""The costmap's layers: ray-traced clearing leaves no ghost, marking, nav2's inflation costs."""

import numpy as np
import pytest

from amr_twin.navigation.costmap import INSCRIBED, LETHAL, Costmap, inflation_cost

from nav_grids import room


def _scan(origin, targets, max_range=12.0, n=360):
    """Beams from ``origin`` over a full turn; each hits the nearest of ``targets`` (discs (x, y,
    r)) or the room's walls (12 x 8 m room), as a LiDAR would: origins (n, 2), ends (n, 2), hit
    (n,)."""
    ang = np.linspace(-np.pi, np.pi, n, endpoint=False)
    d = np.column_stack([np.cos(ang), np.sin(ang)])
    o = np.asarray(origin, float)
    dx = np.where(np.abs(d[:, 0]) > 1e-9, d[:, 0], 1e-9)
    dy = np.where(np.abs(d[:, 1]) > 1e-9, d[:, 1], 1e-9)
    tx = np.where(dx > 0, (12.0 - 0.1 - o[0]) / dx, (0.1 - o[0]) / dx)
    ty = np.where(dy > 0, (8.0 - 0.1 - o[1]) / dy, (0.1 - o[1]) / dy)
    r = np.minimum(tx, ty)
    for x, y, rad in targets:  # ray-disc intersection
        f = o - np.array([x, y])
        b = d @ f
        disc = b * b - (f @ f - rad * rad)
        t = -b - np.sqrt(np.maximum(disc, 0.0))
        r = np.where((disc > 0) & (t > 0) & (t < r), t, r)
    hit = r < max_range
    return np.tile(o, (n, 1)), o + d * np.minimum(r, max_range)[:, None], hit


@pytest.fixture
def costmap():
    return Costmap(room(), inscribed_radius_m=0.265, inflation_radius_m=1.0, cost_scaling_per_m=3.0)


def test_a_person_who_walks_away_leaves_no_obstacle_once_the_scan_has_cleared_it(costmap):
    person = (6.0, 4.0, 0.25)
    costmap.update_scan(*_scan((3.0, 4.0), [person]), obstacle_range_m=4.0, raytrace_range_m=5.0)
    near = costmap.distance_at(np.array([[6.0 - 0.25, 4.0]]))[0]
    assert costmap.marked.sum() >= 3 and near == 0.0  # the person is in the obstacle layer, lethal
    assert costmap.cost()[int(4.0 / 0.05), int(5.6 / 0.05)] >= INSCRIBED  # and inflated around
    costmap.update_scan(*_scan((3.0, 4.0), []), obstacle_range_m=4.0, raytrace_range_m=5.0)  # gone
    assert costmap.marked.sum() == 0
    assert np.array_equal(costmap.dist_m, costmap.static_dist_m)  # no ghost in the inflation either


def test_clearing_stops_at_the_raytrace_range(costmap):
    person = (9.0, 4.0, 0.25)  # 6 m from the laser: marked from 3.5 m away, not cleared from 6 m
    costmap.update_scan(*_scan((3.0, 4.0), [person]), obstacle_range_m=4.0, raytrace_range_m=5.0)
    assert costmap.marked.sum() == 0  # beyond the marking range
    costmap.update_scan(*_scan((5.5, 4.0), [person]), obstacle_range_m=4.0, raytrace_range_m=5.0)
    assert costmap.marked.sum() > 0
    costmap.update_scan(*_scan((3.0, 4.0), []), obstacle_range_m=4.0, raytrace_range_m=5.0)
    assert costmap.marked.sum() > 0  # its cells are 5.75 m away: beyond the clearing range


def test_returns_on_the_static_map_are_not_marked_twice(costmap):
    costmap.update_scan(*_scan((6.0, 4.0), []), obstacle_range_m=12.0, raytrace_range_m=12.0)
    assert costmap.marked.sum() == 0  # every return is a wall of the map


def test_inflation_costs_are_nav2s():
    d = np.array([0.0, 0.1, 0.265, 0.3, 0.6, 0.99, 1.2])
    c = inflation_cost(d, 0.265, 1.0, 3.0)
    assert c[0] == LETHAL and c[1] == INSCRIBED and c[2] == INSCRIBED
    assert c[3] == int(252 * np.exp(-3.0 * (0.3 - 0.265)))
    assert list(c[3:6]) == sorted(c[3:6], reverse=True) and c[5] > 0 and c[6] == 0


def test_each_scan_leaves_the_layers_as_a_rebuild_from_scratch_would():
    """The update touches only the cells that changed (and their inflation window): after people
    walk about, the obstacle layer's distances equal a distance transform of the whole grid, and a
    scan that changes nothing is no change (no new version: the planner skips its replan)."""
    from scipy.ndimage import distance_transform_edt

    cm = Costmap(room(), inscribed_radius_m=0.265, inflation_radius_m=1.0, cost_scaling_per_m=3.0)
    rng = np.random.default_rng(4)
    for k in range(12):
        people = [
            (float(x), float(y), 0.2) for x, y in rng.uniform([2.0, 2.0], [10.0, 6.0], (3, 2))
        ]
        cm.update_scan(*_scan((rng.uniform(1.0, 11.0), rng.uniform(1.0, 7.0)), people), 4.0, 5.0)
    full = np.minimum(distance_transform_edt(~(cm.static_lethal | cm.marked)) * 0.05, 1.05)
    assert cm.marked.any() and np.allclose(cm.dist_m, full, atol=1e-5)
    version = cm.version
    origin = (6.0, 4.0)
    cm.update_scan(*_scan(origin, [(8.0, 4.0, 0.2)]), 4.0, 5.0)
    assert cm.version == version + 1
    assert (
        cm.update_scan(*_scan(origin, [(8.0, 4.0, 0.2)]), 4.0, 5.0) == 0
        and cm.version == version + 1
    )


def test_the_c_clearing_march_leaves_the_layers_of_its_numpy_twin():
    """Scans from random places with random people about, some beams without a return and some ends
    off the grid: the C march (costmap_rays.c) and its NumPy twin clear the same cells, so the two
    costmaps keep the same obstacle layer and distances scan after scan."""
    fast = Costmap(room(), inscribed_radius_m=0.265, inflation_radius_m=1.0, cost_scaling_per_m=3.0)
    slow = Costmap(
        room(),
        inscribed_radius_m=0.265,
        inflation_radius_m=1.0,
        cost_scaling_per_m=3.0,
        native=False,
    )
    if fast.engine != "C":
        pytest.skip(f"the C march is not built here: {fast.engine}")
    rng, cleared = np.random.default_rng(2), 0
    for _ in range(25):
        origin = rng.uniform((0.5, 0.5), (11.5, 7.5))
        people = [
            (*rng.uniform((0.5, 0.5), (11.5, 7.5)), 0.25) for _ in range(int(rng.integers(0, 4)))
        ]
        o, e, hit = _scan(origin, people)
        hit = hit & (rng.random(len(hit)) > 0.1)  # dropped returns: cleared to the raytrace range
        e = np.where(
            rng.random((len(e), 1)) < 0.05, e + rng.uniform(-30, 30, e.shape), e
        )  # some far off the grid
        before = fast.marked.sum()
        changed = [
            cm.update_scan(o, e, hit, obstacle_range_m=4.0, raytrace_range_m=5.0)
            for cm in (fast, slow)
        ]
        assert changed[0] == changed[1]
        assert np.array_equal(fast.marked, slow.marked) and np.array_equal(fast.dist_m, slow.dist_m)
        cleared += int(before > 0 and changed[0] > 0)
    assert fast.marked.sum() > 0 and cleared >= 5  # the scans did mark and clear


def test_the_c_march_crosses_the_cells_its_numpy_twin_crosses_on_a_dense_random_layer():
    """Every sample counts on a layer a third marked: the same crossed cells, in the same order,
    from beams of random origins, directions and free lengths (none, zero, past the grid's edge)."""
    fast = Costmap(room(), inscribed_radius_m=0.265, inflation_radius_m=1.0, cost_scaling_per_m=3.0)
    slow = Costmap(
        room(),
        inscribed_radius_m=0.265,
        inflation_radius_m=1.0,
        cost_scaling_per_m=3.0,
        native=False,
    )
    if fast.engine != "C":
        pytest.skip(f"the C march is not built here: {fast.engine}")
    rng = np.random.default_rng(6)
    for cm in (fast, slow):
        cm.marked[:] = np.random.default_rng(1).random(cm.shape) < 0.33
    for _ in range(5):
        n = 200
        o = rng.uniform((-1.0, -1.0), (13.0, 9.0), (n, 2))
        a = rng.uniform(-np.pi, np.pi, n)
        u = np.column_stack([np.cos(a), np.sin(a)])
        free = np.where(rng.random(n) < 0.1, rng.uniform(-0.5, 0.0, n), rng.uniform(0.0, 6.0, n))
        free[::17] = 0.0  # a beam whose return is within half a cell: clears nothing
        got, want = fast._crossed(o, u, free), slow._crossed(o, u, free)
        assert len(want) > 1000 and np.array_equal(got, want)
