"""The navigation experiment's SLAM map (experiments/navigation/map.py), from a shortened mapping
drive.

The aisles' mapping route cut to its first four waypoints (108 m, the side aisle and the first
aisle between rack rows, a U-turn): the drive, the pose graph, the scan matcher and the saved map,
as `amr-twin experiment navigation` builds them, on two seeds (12 s of CPU each).
"""

from __future__ import annotations

import pytest
import yaml

from amr_twin.experiments.navigation import map as navigation_map
from amr_twin.model.config import load_config
from amr_twin.model.occupancy_map import load_map


@pytest.fixture
def short_route(tmp_path, monkeypatch):
    tree = yaml.safe_load(navigation_map.mapping_route("aisles").read_text())
    tree["waypoints_xy_m"] = tree["waypoints_xy_m"][:4]
    path = tmp_path / "aisles_mapping.yaml"
    path.write_text(yaml.safe_dump(tree))
    monkeypatch.setattr(navigation_map, "mapping_route", lambda world: path)
    return path


@pytest.mark.parametrize("seed", [0, 1])
def test_the_slam_map_lies_on_the_world_where_the_ekf_poses_would_not(short_route, tmp_path, seed):
    out = navigation_map.build_slam_map(load_config(), "aisles", tmp_path / "slam_map", seed=seed)
    assert out["reached"]
    # measured: 99.95 and 99.89 % (the EKF's poses: 66.9 and 79.2 %; the truth's: 99.98-100 %)
    assert out["walls_within_2_cells_frac"] > 0.98
    assert out["ekf_only_walls_within_2_cells_frac"] < 0.9
    assert out["pose_graph"]["ranges_used"] > 4000
    grid = load_map(tmp_path / "slam_map.yaml")
    assert grid.resolution_m == pytest.approx(0.05)
    assert (
        not (tmp_path / "slam_map_unmatched.yaml").exists()
        and not (tmp_path / "slam_map_ekf_only.yaml").exists()
    )


def test_a_world_without_a_mapping_route_is_refused_in_one_line():
    with pytest.raises(ValueError, match="world nowhere: no mapping route"):
        navigation_map.mapping_route("nowhere")
