"""The mapping drive's smoother (amr_twin/estimation/pose_graph.py) on synthetic drives with known
truth.

A snake through a 24 x 12 m hall at 1 m/s; the wheel odometry with a 1 % scale and 0.5 deg/s of
turn error in each U-turn; "LiDAR odometry" that slides along the legs (3 % of the distance) and
drifts 1 deg in heading over the drive; UWB ranges round-robin to four anchors from the twin's
range model (sensors/uwb.py) with 30 % of them late (NLOS, mean 0.5 m). The smoother must put
the poses within 8 cm and 0.6 deg (p95; it gives 5.5-5.8 cm and 0.38-0.40 deg) where the LiDAR
odometry alone is 2.7 m off and the wheel odometry 11 m and 7 deg.
"""

from __future__ import annotations

import numpy as np
import pytest

from amr_twin.analysis import se2
from amr_twin.estimation.pose_graph import smooth
from amr_twin.model.config import load_config
from amr_twin.sensors.uwb import simulate_ranges, tag_positions_m

SCAN_HZ, ODOM_HZ, UWB_HZ = 5.5, 100.0, 40.0
ANCHORS = np.array([[12.5, 6.5], [-12.5, 6.5], [-12.5, -6.5], [12.5, -6.5]])


def _snake(dt: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Truth: stamps, poses (N, 3), and the yaw rate (N,) of a snake of 20 m legs 3 m apart at 1
    m/s."""
    w_turn = 1.0 / 1.5  # a U-turn of radius 1.5 m at 1 m/s
    segments = []
    for leg in range(4):
        segments += [(20.0, 0.0), (np.pi / w_turn, w_turn if leg % 2 == 0 else -w_turn)]
    w = np.concatenate([np.full(int(round(length / dt)), rate) for length, rate in segments])
    yaw = np.concatenate([[0.0], np.cumsum(w[:-1]) * dt])
    x = -10.0 + np.concatenate([[0.0], np.cumsum(np.cos(yaw[:-1])) * dt])
    y = -5.0 + np.concatenate([[0.0], np.cumsum(np.sin(yaw[:-1])) * dt])
    return np.arange(len(w)) * dt, np.column_stack([x, y, yaw]), w


def _drive(seed: int, scan_hz: float = SCAN_HZ):
    cfg = load_config()
    rng = np.random.default_rng(seed)
    t, truth, w = _snake(1.0 / ODOM_HZ)
    dt = 1.0 / ODOM_HZ
    # wheel odometry: 1 % long, turns 0.5 deg/s off, the heading's slip a random walk (the twin's
    # 0.0036 rad std over a scan, 0.18 s), integrated from the origin
    v_odom = 1.01
    w_odom = (
        w
        + np.where(w != 0, np.radians(0.5), 0.0)
        + rng.normal(0.0, 0.0036 / np.sqrt(18) / dt, len(w))
    )
    yaw = np.concatenate([[0.0], np.cumsum(w_odom[:-1]) * dt])
    odom = np.column_stack(
        [
            np.concatenate([[0.0], np.cumsum(v_odom * np.cos(yaw[:-1])) * dt]),
            np.concatenate([[0.0], np.cumsum(v_odom * np.sin(yaw[:-1])) * dt]),
            yaw,
        ]
    )
    # LiDAR odometry at the scans: slides 3 % along each leg, heading drifting 1 deg over the drive
    t_scan = np.arange(0.0, t[-1], 1.0 / scan_hz)
    at = se2.interpolate(t, truth, t_scan).reshape(-1, 3)
    slide = 0.03 * np.cumsum(np.abs(np.cos(at[:, 2]))) / scan_hz
    lidar = at + np.column_stack(
        [slide, np.zeros_like(slide), np.radians(1.0) * t_scan / t_scan[-1]]
    )
    lidar[:, :2] += rng.normal(0.0, 0.003, (len(t_scan), 2))
    # UWB: the twin's range model, 30 % late
    uwb = cfg.uwb.model_copy(update={"nlos_prob": 0.3})
    t_uwb = np.arange(0.0, t[-1], 1.0 / UWB_HZ)
    tag = tag_positions_m(se2.interpolate(t, truth, t_uwb).reshape(-1, 3), uwb.tag_pos_m)
    ranges = simulate_ranges(
        t_uwb, tag, ANCHORS, uwb, rng, anchor=np.arange(len(t_uwb)) % len(ANCHORS)
    )
    return cfg, uwb, (t, truth), (t, odom), (t_scan, lidar), ranges


def _errors(t_s, pose, t_true, truth) -> tuple[float, float]:
    ref = se2.interpolate(t_true, truth, t_s).reshape(-1, 3)
    return (
        float(np.percentile(np.hypot(*(pose[:, :2] - ref[:, :2]).T), 95)),
        float(np.degrees(np.percentile(np.abs(se2.wrap_rad(pose[:, 2] - ref[:, 2])), 95))),
    )


def _smooth(cfg, uwb, odom, lidar, ranges, **change):
    graph = cfg.mapping.pose_graph.model_copy(update=change)
    tag = np.asarray(uwb.tag_pos_m)
    return smooth(
        lidar[0],
        lidar[1],
        odom[0],
        odom[1],
        ranges,
        ANCHORS,
        tag[:2],
        uwb.anchor_z_m - tag[2],
        lidar[1][0],
        cfg.ekf.uwb_range_sigma_m,
        graph,
    )


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_smoothed_drive_is_within_centimetres_where_each_odometry_is_not(seed):
    cfg, uwb, true, odom, lidar, ranges = _drive(seed)
    lidar_xy, lidar_yaw = _errors(*lidar, *true)
    odom_xy, odom_yaw = _errors(odom[0], odom[1], *true)
    assert lidar_xy > 0.8 and odom_yaw > 3.0  # the drive is hard for either alone
    out = _smooth(cfg, uwb, odom, lidar, ranges)
    xy, yaw = _errors(out.t_s, out.pose, *true)
    assert xy < 0.08, xy
    assert yaw < 0.6, yaw
    assert out.ranges_used > 0.9 * len(ranges)


@pytest.mark.parametrize("seed", [0, 1])
def test_each_range_is_placed_at_its_own_instant(seed):
    """At one scan a second a range is up to 0.5 s (0.5 m) from its pose: the odometry's motion over
    that time places the tag."""
    cfg, uwb, true, odom, lidar, ranges = _drive(seed, scan_hz=1.0)
    out = _smooth(cfg, uwb, odom, lidar, ranges)
    assert _errors(out.t_s, out.pose, *true)[0] < 0.14  # 0.11 m; 0.18 m with the tag at the node


def test_late_ranges_weigh_little():
    """Without the Cauchy weighting (a huge k: every range quadratic) the late ranges pull the
    poses."""
    cfg, uwb, true, odom, lidar, ranges = _drive(0)
    robust = _errors(*(lambda o: (o.t_s, o.pose))(_smooth(cfg, uwb, odom, lidar, ranges)), *true)[0]
    plain = _errors(
        *(lambda o: (o.t_s, o.pose))(_smooth(cfg, uwb, odom, lidar, ranges, uwb_cauchy_k=100.0)),
        *true,
    )[0]
    assert plain > 1.5 * robust, (plain, robust)


def test_bad_inputs_are_refused_in_one_line():
    cfg, uwb, true, odom, lidar, ranges = _drive(0)
    t_scan = lidar[0].copy()
    t_scan[5] = t_scan[4]
    with pytest.raises(ValueError, match="t_s: .* strictly increasing"):
        _smooth(cfg, uwb, odom, (t_scan, lidar[1]), ranges)
    with pytest.raises(ValueError, match="uwb_anchor_3 is not one of the 3 anchors"):
        tag = np.asarray(uwb.tag_pos_m)
        smooth(
            lidar[0],
            lidar[1],
            odom[0],
            odom[1],
            ranges,
            ANCHORS[:3],
            tag[:2],
            2.0,
            lidar[1][0],
            0.08,
            cfg.mapping.pose_graph,
        )
