"""One fusion drive's typed metrics (experiments/fusion/metrics.py): the verdicts and metrics.json's
shape."""

import dataclasses
import json
from types import SimpleNamespace

import numpy as np

from amr_twin.analysis.trajectory import TrajectoryErrors
from amr_twin.experiments.fusion.experiment import ARCHITECTURES
from amr_twin.experiments.fusion.map import TOLERANCE_CELLS, MapAgreement
from amr_twin.experiments.fusion.metrics import LIDAR_ATE_MAX_M, FusionMetrics, metrics

MAP = MapAgreement(100, 0.97, 1.0, 3.0, 0.9)


def _errors(**kw) -> TrajectoryErrors:
    base = {f.name: 0.5 for f in dataclasses.fields(TrajectoryErrors)}
    return TrajectoryErrors(**{**base, "length_m": 60.0, **kw})


def _results(lidar_ate_m: float, imu_rms_deg: float) -> SimpleNamespace:
    errors = {name: _errors() for name in ARCHITECTURES}
    errors["odom"] = _errors(final_pos_err_m=1.5, rms_yaw_err_deg=2.0)
    errors["odom+lidar"] = _errors(ate_m=lidar_ate_m)
    errors["odom+imu"] = _errors(rms_yaw_err_deg=imu_rms_deg)
    estimates = {
        name: SimpleNamespace(errors=e, ate_aligned_m=0.1, wall_s=0.2) for name, e in errors.items()
    }
    return SimpleNamespace(
        route=SimpleNamespace(name="r", world="warehouse", max_speed_m_s=1.0),
        seed=4,
        firmware="improved",
        sim_s=67.0,
        drive_wall_s=3.0,
        wall_s=6.0,
        message_counts={"odom": 3},
        anchors_xy_m=np.zeros((4, 2)),
        uwb_exchanges=10,
        uwb_blocked=[1, 0, 0, 2],
        robot=None,
        estimates=estimates,
        reached_goal=True,
        cross_track_rms_m=0.03,
    )


def test_the_verdicts_judge_the_right_architectures_against_their_limits():
    files = {name: f"{name}.tum" for name in ARCHITECTURES}
    good = metrics(_results(LIDAR_ATE_MAX_M - 1e-3, 1.0), MAP, files).summary
    assert good.lidar_ate_under_0_10_m and good.imu_beats_odom_on_heading
    assert good.odom_drift_final_m == 1.5 and good.odom_drift_pct_of_length == 2.5
    bad = metrics(
        _results(LIDAR_ATE_MAX_M, 2.0), MAP, files
    ).summary  # at the limit: not under it; no better
    assert not bad.lidar_ate_under_0_10_m and not bad.imu_beats_odom_on_heading
    assert good.map_walls_within_2_cells_frac == 0.97 and good.reached_goal


def test_the_json_is_written_from_the_records():
    m = metrics(_results(0.05, 1.0), MAP, {name: f"{name}.tum" for name in ARCHITECTURES})
    assert isinstance(m, FusionMetrics)
    out = json.loads(json.dumps(m.as_json(), allow_nan=False))
    assert list(out) == [
        "route",
        "seed",
        "firmware",
        "sim_s",
        "drive_wall_s",
        "wall_s",
        "messages",
        "uwb",
        "robot",
        "rpe_delta_m",
        "architectures",
        "map",
        "summary",
    ]
    assert out["route"]["length_m"] == 60.0 and out["uwb"]["anchors_xy_m"] == [[0.0, 0.0]] * 4
    lidar = out["architectures"]["odom+lidar"]
    assert lidar["ate_m"] == 0.05 and list(lidar)[-3:] == ["ate_aligned_m", "wall_s", "tum"]
    assert lidar["tum"] == "odom+lidar.tum"
    assert out["map"] == {"tolerance_cells": TOLERANCE_CELLS, **dataclasses.asdict(MAP)}
