"""Occupancy grid: a synthetic square room (no mujoco), map_server files, then the warehouse from
twin scans."""

import math

import numpy as np
import pytest
import yaml

from amr_twin.estimation.occupancy_grid import FREE_THRESH, OccupancyGrid
from amr_twin.ros.messages import Header, Time
from amr_twin.ros.sensor_messages import LaserScan
from amr_twin.model.occupancy_map import load_map
from amr_twin.model.pgm import read_pgm
from amr_twin.recording.recorder import attach_recorder, recorder_of

HALF_M = 2.0  # the room's inner faces at x, y = +-2 m
RES_M = 0.05
N_BEAMS = 360


def square_ranges(x_m, y_m, world_angle_rad):
    """Distance from (x, y) inside the room to its walls along world angles, m."""
    c, s = np.cos(world_angle_rad), np.sin(world_angle_rad)
    with np.errstate(divide="ignore"):
        tx = np.where(c > 0, (HALF_M - x_m) / c, (-HALF_M - x_m) / c)
        ty = np.where(s > 0, (HALF_M - y_m) / s, (-HALF_M - y_m) / s)
    return np.minimum(np.where(tx > 0, tx, np.inf), np.where(ty > 0, ty, np.inf))


def make_scan(ranges) -> LaserScan:
    inc = 2 * math.pi / N_BEAMS
    return LaserScan(
        header=Header(0, Time.from_sec(1.0), "laser"),
        angle_min=-math.pi,
        angle_max=-math.pi + inc * (N_BEAMS - 1),
        angle_increment=inc,
        time_increment=0.0005,
        scan_time=0.18,
        range_min=0.15,
        range_max=12.0,
        ranges=np.asarray(ranges, np.float32),
    )


def room_scan(poses: np.ndarray) -> LaserScan:
    """Beam i cast from laser pose ``poses[i]`` (N_BEAMS, 3)."""
    ang = poses[:, 2] - math.pi + 2 * math.pi / N_BEAMS * np.arange(N_BEAMS)
    return make_scan(square_ranges(poses[:, 0], poses[:, 1], ang))


def wall_distance_m(xy):
    """Distance of points to the square's outline, m."""
    return np.abs(np.max(np.abs(xy), axis=1) - HALF_M)


def new_grid(**kw) -> OccupancyGrid:
    return OccupancyGrid(RES_M, 6.0, 6.0, (-3.0, -3.0), **kw)


def test_square_room_walls_free_inside_unknown_outside():
    grid = new_grid()
    pose = (0.1, -0.2, 0.3)
    for _ in range(5):
        grid.insert_scan(pose, room_scan(np.tile(pose, (N_BEAMS, 1))))
    assert grid.log_odds.shape == (120, 120)
    occ = grid.cell_centres_xy(grid.occupied())
    assert len(occ) > 4 * 2 * HALF_M / RES_M * 0.9  # the four walls, nearly every cell
    assert wall_distance_m(occ).max() <= RES_M  # each within one cell of a wall
    p = grid.probabilities()
    xy = grid.cell_centres_xy(np.ones_like(p, bool))
    inner = np.max(np.abs(xy), axis=1) < HALF_M - 2 * RES_M
    outer = np.max(np.abs(xy), axis=1) > HALF_M + 2 * RES_M
    assert np.all(p.reshape(-1)[inner] < FREE_THRESH)
    assert np.all(grid.log_odds.reshape(-1)[outer] == 0.0)  # never seen: unknown


def test_each_scan_updates_a_cell_once_hits_win_and_log_odds_are_clamped():
    grid = new_grid()
    pose = (0.0, 0.0, 0.0)
    scan = room_scan(np.tile(pose, (N_BEAMS, 1)))
    grid.insert_scan(pose, scan)
    values = np.unique(grid.log_odds)
    np.testing.assert_allclose(sorted(values), sorted([grid.l_free, 0.0, grid.l_occ]), rtol=1e-6)
    for _ in range(60):
        grid.insert_scan(pose, scan)
    assert grid.log_odds.max() == pytest.approx(grid.l_max, rel=1e-6)
    assert grid.log_odds.min() == pytest.approx(grid.l_min, rel=1e-6)
    assert grid.scans_inserted == 61


def test_beams_without_return_mark_nothing_unless_asked():
    ranges = np.full(N_BEAMS, np.inf)
    ranges[:10] = 12.0  # at range_max: no return either
    ranges[10:20] = 0.05  # below range_min: ignored
    grid = new_grid()
    grid.insert_scan((0.0, 0.0, 0.0), make_scan(ranges))
    assert not grid.log_odds.any()
    grid = new_grid(free_on_no_return=True)
    grid.insert_scan((0.0, 0.0, 0.0), make_scan(ranges))
    assert not grid.occupied().any()
    assert (
        grid.log_odds < 0
    ).sum() > 0.9 * math.pi * 3.0**2 / RES_M**2  # the disc inside the 6 m grid


def test_beam_poses_of_a_moving_laser_straighten_the_walls():
    # one rotation while moving 0.3 m along x and turning 10 deg
    s = np.linspace(0.0, 1.0, N_BEAMS)
    poses = np.column_stack([-0.5 + 0.3 * s, 0.2 + 0.0 * s, math.radians(10.0) * s])
    scan = room_scan(poses)
    per_beam, one_pose = new_grid(), new_grid()
    per_beam.insert_scan(None, scan, beam_poses=poses)
    one_pose.insert_scan(tuple(poses[-1]), scan)
    assert wall_distance_m(per_beam.cell_centres_xy(per_beam.occupied())).max() <= RES_M
    assert wall_distance_m(one_pose.cell_centres_xy(one_pose.occupied())).max() > 2 * RES_M


def test_points_off_the_grid_are_ignored():
    grid = OccupancyGrid(RES_M, 1.0, 1.0, (0.0, 0.0))  # only a corner of the room
    grid.insert_scan((0.5, 0.5, 0.0), room_scan(np.tile((0.5, 0.5, 0.0), (N_BEAMS, 1))))
    assert not grid.occupied().any() and (grid.log_odds < 0).all()


def test_bad_input_is_refused_with_the_field_name():
    with pytest.raises(ValueError, match="resolution_m"):
        OccupancyGrid(0.0, 1.0, 1.0, (0.0, 0.0))
    with pytest.raises(ValueError, match="hit_prob"):
        OccupancyGrid(0.05, 1.0, 1.0, (0.0, 0.0), hit_prob=0.4)
    grid = new_grid()
    scan = room_scan(np.zeros((N_BEAMS, 3)))
    with pytest.raises(ValueError, match="beam_poses"):
        grid.insert_scan(None, scan, beam_poses=np.zeros((N_BEAMS - 1, 3)))
    with pytest.raises(ValueError, match="laser_pose_xy_yaw"):
        grid.insert_scan((0.0, math.inf, 0.0), scan)


def test_save_writes_map_server_files_that_the_world_loader_reads(tmp_path):
    grid = new_grid()
    for pose in ((0.0, 0.0, 0.0), (0.5, 0.5, 1.0)) * 2:  # 4 misses make a cell free (p < 0.196)
        grid.insert_scan(pose, room_scan(np.tile(pose, (N_BEAMS, 1))))
    yaml_path, pgm_path, png_path = grid.save(tmp_path / "maps" / "room.v1")
    assert (yaml_path.name, pgm_path.name, png_path.name) == (
        "room.v1.yaml",
        "room.v1.pgm",
        "room.v1.png",
    )
    meta = yaml.safe_load(yaml_path.read_text())
    assert meta == {
        "image": "room.v1.pgm",
        "resolution": RES_M,
        "origin": [-3.0, -3.0, 0.0],
        "mode": "trinary",
        "negate": 0,
        "occupied_thresh": 0.65,
        "free_thresh": 0.196,
    }
    image = read_pgm(pgm_path)
    assert set(np.unique(image).tolist()) == {0, 205, 254}
    loaded = load_map(yaml_path)
    np.testing.assert_array_equal(
        loaded.occupied[::-1], grid.occupied()
    )  # image top row = highest y
    assert loaded.resolution_m == RES_M and loaded.origin_xyyaw == (-3.0, -3.0, 0.0)
    assert png_path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    import matplotlib.image

    assert matplotlib.image.imread(png_path).shape[:2] == image.shape


# -- twin scans ---------------------------------------------------------------------
@pytest.fixture(scope="module")
def warehouse_scans():
    """10 s near the east wall: 0.6 m/s east for 4 s, then one turn in place; scans and the true
    pose."""
    from amr_twin.model.config import load_config
    from amr_twin.assembly.twin import Twin, TwinOptions
    from amr_twin.model.world_geometry import scan_plane_boxes

    cfg = load_config()
    twin = Twin(
        cfg,
        TwinOptions(
            sensors=("imu", "lidar"),
            firmware="improved",
            world="warehouse",
            start_xy_yaw=(5.5, 0.5, 0.0),
        ),
    )
    attach_recorder(twin)
    scans = []
    twin.bus.subscribe("scan", scans.append)
    assert twin.client.linear(0.6) == 0
    twin.advance(4.0)
    assert twin.client.angular(60.0, 0.0) == 0
    twin.advance(6.5)
    series = recorder_of(twin).series()
    laser_z_m = float(twin.physics.data.site_xpos[twin.sensors["lidar"].site_id][2])
    boxes = scan_plane_boxes(twin.physics.model, laser_z_m)
    laser_xy_yaw = (cfg.components.lidar.pos_m[0], cfg.components.lidar.pos_m[1], 0.0)
    return scans, series.t_s, series.pose, boxes, laser_xy_yaw


def test_map_from_true_poses_lies_on_the_warehouse_walls(warehouse_scans, tmp_path):
    from amr_twin.analysis import se2
    from amr_twin.estimation.lidar_odometry import beam_times_s
    from amr_twin.model.world_geometry import distance_to_boxes_m

    scans, t_true, pose_true, boxes, laser_xy_yaw = warehouse_scans
    grid = OccupancyGrid(RES_M, 21.0, 15.0, (-10.5, -7.5))
    ends = []
    for scan in scans:
        beams = se2.compose(
            se2.interpolate(t_true, pose_true, beam_times_s(scan)), np.array(laser_xy_yaw)
        )
        grid.insert_scan(None, scan, beam_poses=beams)
        r = np.asarray(scan.ranges, float)
        ok = np.isfinite(r)
        ang = beams[ok, 2] + scan.angle_min + scan.angle_increment * np.flatnonzero(ok)
        ends.append(beams[ok, :2] + r[ok, None] * np.column_stack([np.cos(ang), np.sin(ang)]))
    assert len(scans) >= 55
    yaml_path, _, _ = grid.save(tmp_path / "warehouse")
    loaded = load_map(yaml_path)
    occ = grid.cell_centres_xy(loaded.occupied[::-1])  # what map_server would load
    assert len(occ) > 1000
    dist_cells = distance_to_boxes_m(occ, boxes) / RES_M
    assert np.mean(dist_cells <= 2.0) >= 0.99  # walls within 2 cells
    # the surfaces seen are covered: every true beam end point has an occupied cell within 2 cells
    from scipy.spatial import cKDTree

    d_end, _ = cKDTree(occ).query(np.vstack(ends))
    assert np.mean(d_end <= 2.0 * RES_M) >= 0.98
    # the east wall (inner face x = 10 m) is in the map over the span the robot saw
    east = occ[np.abs(occ[:, 0] - 10.0) <= 2 * RES_M]
    assert east[:, 1].max() - east[:, 1].min() > 10.0
