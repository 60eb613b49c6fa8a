"""The support polygon and the tip margin: against Qhull (scipy) and by hand."""

import numpy as np
import pytest

from amr_twin.model.support_polygon import support_polygon, tip_margin_m


def test_tip_margin_geometry():
    square = np.array([[1, 1], [-1, 1], [-1, -1], [1, -1]], float)
    assert tip_margin_m(square, np.array([0.0, 0.0])) == pytest.approx(1.0)
    assert tip_margin_m(square, np.array([0.5, 0.0])) == pytest.approx(0.5)
    assert tip_margin_m(square, np.array([1.5, 0.0])) == pytest.approx(-0.5)


@pytest.mark.parametrize("seed", range(5))
def test_support_polygon_and_margin_agree_with_scipy_convex_hull(seed):
    """The hand-written hull against Qhull (scipy), on random point sets with the com inside and
    outside."""
    ConvexHull = pytest.importorskip("scipy.spatial").ConvexHull
    rng = np.random.default_rng(seed)
    for n in (3, 4, 6, 9):
        pts = rng.uniform(-0.4, 0.4, (n, 2))
        hull = ConvexHull(pts)
        ours = support_polygon(pts)
        assert sorted(map(tuple, ours.round(12))) == sorted(
            map(tuple, pts[hull.vertices].round(12))
        )
        for com in rng.uniform(-0.6, 0.6, (20, 2)):
            qhull = float(np.min(-(hull.equations[:, :2] @ com + hull.equations[:, 2])))
            assert tip_margin_m(pts, com) == pytest.approx(qhull, abs=1e-12)


def test_supports_in_a_line_have_no_margin():
    line = np.array([[0.0, 0.0], [0.1, 0.0], [0.3, 0.0], [0.2, 0.0]])
    assert tip_margin_m(line, np.array([0.1, 0.0])) == -float("inf")
