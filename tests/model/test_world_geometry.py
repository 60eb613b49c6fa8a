"""Box footprints and point distances (pure part without mujoco, then the warehouse)."""

import math

import numpy as np
import pytest

from amr_twin.model.world_geometry import (
    Footprints,
    distance_to_boxes_m,
    scan_plane_boxes,
    surface_samples_m,
)


def _one_box(yaw: float) -> Footprints:
    return Footprints(np.array([[1.0, 2.0]]), np.array([[0.5, 0.25]]), np.array([yaw]), ("b",))


def test_distance_axis_aligned_and_inside():
    b = _one_box(0.0)
    d = distance_to_boxes_m(np.array([[1.0, 2.0], [2.5, 2.0], [1.0, 3.25], [2.5, 3.25]]), b)
    np.testing.assert_allclose(d, [0.0, 1.0, 1.0, math.hypot(1.0, 1.0)], atol=1e-12)


def test_distance_rotated_box():
    b = _one_box(math.pi / 2)  # long side now along y
    d = distance_to_boxes_m(np.array([[1.0, 3.5], [2.25, 2.0]]), b)
    np.testing.assert_allclose(d, [1.0, 1.0], atol=1e-12)


def test_outline_samples_lie_on_the_outline():
    b = _one_box(0.3)
    pts = surface_samples_m(b, 0.05)
    assert len(pts) > 2 * (1.0 + 0.5) / 0.05
    assert np.all(distance_to_boxes_m(pts, b) < 1e-9)
    grown = Footprints(b.centre_xy_m, b.half_xy_m - 0.01, b.yaw_rad, b.names)
    assert np.all(distance_to_boxes_m(pts, grown) > 0.009)


def test_warehouse_walls_at_lidar_height():
    from amr_twin.model.build import build
    from amr_twin.model.config import load_config

    model = build(load_config(), "warehouse").model
    boxes = scan_plane_boxes(model, 0.45)
    names = set(boxes.names)
    assert {"wall_north", "wall_south", "wall_east", "wall_west", "rack_n_beam_low"} <= names
    assert "rack_n_beam_high" not in names  # 1.5 m high: above the scan plane
    assert not any(n.startswith("amr/") for n in names)
    # the inner face of the east wall is at x = 10.0
    assert distance_to_boxes_m(np.array([[9.0, 0.0]]), boxes)[0] == pytest.approx(1.0, abs=1e-6)
