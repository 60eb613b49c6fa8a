"""The fleet's starts: distinct rack-face nodes of the warehouse's roadmap, nearest the world's
start first, the same node for robot i whatever the fleet's size, no two robots overlapping."""

import math

import pytest

from amr_twin.experiments.fleet.starts import start_poses
from amr_twin.fleet_manager.roadmap import world_roadmap
from amr_twin.model.config import load_config
from amr_twin.model.robot_starts import overlapping_starts
from amr_twin.model.worlds import default_start


@pytest.fixture(scope="module")
def setup():
    cfg = load_config()
    return cfg, world_roadmap(cfg, "warehouse")


def test_twenty_robots_start_on_distinct_rack_faces_without_overlap(setup):
    cfg, roadmap = setup
    half = (cfg.chassis.length_m / 2, cfg.half_width_m)
    poses = start_poses(roadmap, default_start("warehouse")[:2], 20, *half)
    faces = {roadmap.xy(n): n for n in roadmap.nodes_of("aisle")}
    nodes = [faces[min(faces, key=lambda xy: math.dist(xy, p[:2]))] for p in poses]
    assert len(set(nodes)) == 20
    assert all(math.dist(roadmap.xy(n), p[:2]) < 0.01 for n, p in zip(nodes, poses))
    assert overlapping_starts(poses, *half) is None
    near = [math.dist(p[:2], default_start("warehouse")[:2]) for p in poses]
    assert near == sorted(near)  # nearest the start first
    assert start_poses(roadmap, default_start("warehouse")[:2], 4, *half) == poses[:4]


def test_more_robots_than_rack_faces_is_one_line(setup):
    cfg, roadmap = setup
    with pytest.raises(ValueError, match=r"^--robots 40: map 'warehouse' has 23 rack-face nodes"):
        start_poses(roadmap, (0.0, 0.0), 40, cfg.chassis.length_m / 2, cfg.half_width_m)
