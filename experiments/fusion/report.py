"""Tables of the fusion experiment: :func:`report` saves the map (``map.yaml``, ``map.pgm``,
``map.png``), judges it, and writes the TUM trajectories, ``metrics.json`` and ``report.md`` (the
figures are :func:`.plot.plot`'s). Every file goes through a temporary file and a rename.
"""

from __future__ import annotations

from pathlib import Path

from amr_twin.experiments.runner.executor import write_json, write_text
from amr_twin.experiments.fusion.experiment import ARCHITECTURES
from amr_twin.experiments.fusion.results import FusionResults
from amr_twin.experiments.fusion.metrics import LIDAR_ATE_MAX_M, FusionMetrics, metrics
from amr_twin.experiments.fusion.map import agreement
from amr_twin.analysis import tum
from amr_twin.base import atomic_file


def _save_map(results: FusionResults, out: Path):
    """Save the grid as map.yaml/.pgm/.png in ``out`` via a staging folder; return its check.

    The map is judged as saved (read back from the staging folder) and then moved
    into ``out`` with the other outputs (:func:`amr_twin.base.atomic_file.all_or_nothing`).
    """
    staging = atomic_file.temporary_name(out / "map")
    staging.mkdir(parents=True, exist_ok=True)
    try:
        written = results.grid.save(staging / "map")
        map_check = agreement(staging / "map.yaml", results.boxes)
        for path in written:
            atomic_file.place(path, out / Path(path).name)
    finally:
        atomic_file.discard_after(staging)
    return map_check


def tum_name(name: str) -> str:
    """File name of an architecture's TUM trajectory: ``odom+uwb+imu`` -> ``odom_uwb_imu.tum``."""
    return name.replace("+", "_") + ".tum"


def write_trajectories(results: FusionResults, out: Path) -> dict[str, str]:
    """Write ``truth.tum`` and one TUM file per architecture into ``out``; return {architecture:
    file name}.

    The truth is sampled at its 100 Hz record and at every estimate's stamps
    (:func:`amr_twin.analysis.tum.truth_at`), so that evo's nearest-stamp association pairs each
    estimate pose with the true pose of its own instant.
    """
    out = Path(out)
    ests = [results.estimates[name] for name in ARCHITECTURES]
    t_truth, pose_truth = tum.truth_at(results.t_true_s, results.pose_true, [e.t_s for e in ests])
    tum.write(out / "truth.tum", t_truth, pose_truth)
    for est in ests:
        tum.write(out / tum_name(est.name), est.t_s, est.pose)
    return {est.name: tum_name(est.name) for est in ests}


def evo_commands(folder: str = "DIR", name: str = "odom_uwb_imu.tum") -> list[str]:
    """The evo commands that reproduce an architecture's ATE (plain, aligned) and RPE from the TUM
    files."""
    ref, est = f"{folder}/truth.tum", f"{folder}/{name}"
    return [
        f"evo_ape tum {ref} {est}",
        f"evo_ape tum {ref} {est} --align",
        f"evo_rpe tum {ref} {est} --delta 1 --delta_unit m --all_pairs --pairs_from_reference",
        f"evo_rpe tum {ref} {est} --delta 1 --delta_unit m --all_pairs --pairs_from_reference "
        f"-r angle_deg",
    ]


DEFINITIONS = [
    "- **ATE m**: RMS of the position error |p_est(t) - p_true(t)| over the estimate's samples, "
    "the truth "
    "interpolated at each stamp, **without alignment** (every estimate starts from the known "
    "start pose, "
    "in the map frame); evo's `evo_ape` default (translation part, RMSE).",
    "- **ATE aligned m**: the same after the least-squares SE(2) alignment of the estimate onto "
    "the truth "
    "(Umeyama/Horn, no scale; `evo_ape --align`): what is left when a constant offset of the whole "
    "trajectory is forgiven. It removes the effect of an early heading error and so favours "
    "drifting "
    "estimates.",
    "- **RPE m / 1 m, deg / 1 m**: RMS of the translation and rotation error of the relative "
    "motion over "
    "every pair of samples about 1 m of true travel apart (the nearest, within 10 %; evo's "
    "`evo_rpe "
    "--delta 1 --delta_unit m --all_pairs --pairs_from_reference`).",
    "- **final** errors at the estimate's last sample; **RMS / max heading** over all samples.",
]


def report(results: FusionResults, out: Path, figures: bool = True) -> FusionMetrics:
    """Save the map and the TUM trajectories, write ``metrics.json`` (from the typed
    :class:`~.metrics.FusionMetrics`) and ``report.md``; return the metrics.

    ``figures``: the report shows ``trajectories.png`` and ``errors.png`` (written by
    :func:`.plot.plot`).
    """
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    map_check = _save_map(results, out)
    files = write_trajectories(results, out)
    data = metrics(results, map_check, files)
    written = data.as_json()
    write_json(out / "metrics.json", written)
    write_text(out / "report.md", markdown(written, figures))
    return data


def _yaw(data: dict, name: str) -> str:
    e = data["architectures"][name]
    return (
        f"RMS {e['rms_yaw_err_deg']:.2f} deg, max {e['max_yaw_err_deg']:.2f} deg, "
        f"final {e['final_yaw_err_deg']:.2f} deg"
    )


def robot_line(robot: dict | None) -> str:
    """One sentence on the robot's own errors of this seed (``FusionResults.robot``)."""
    if not robot:
        return ""
    what = (
        "drawn for this seed"
        if robot["drawn"]
        else "none: the robot is exactly as its odometry assumes"
    )
    return (
        f"The robot's own errors ({what}): tyre radii {1e3 * robot['radius_error_left_m']:+.2f} "
        f"mm left, "
        f"{1e3 * robot['radius_error_right_m']:+.2f} mm right, track "
        f"{1e3 * robot['separation_error_m']:+.2f} mm "
        f"(the odometry assumes the nominal geometry: distance "
        f"{100 * robot['odom_distance_error']:+.2f} %, "
        f"heading drift {robot['odom_heading_drift_deg_per_m']:+.3f} deg per metre of straight, "
        f"turns "
        f"{100 * robot['odom_turn_error']:+.2f} %); hall sensors off by up to "
        f"{max(abs(v) for row in robot['hall_misalignment_deg'] for v in row):.2f} deg, edge "
        f"jitter "
        f"{robot['hall_jitter_us']:.1f} us; gyro scale error {100 * robot['gyro_scale_z']:+.2f} %."
    )


def markdown(data: dict, figures: bool = True) -> str:
    """``report.md`` from the metrics (``figures``: link ``trajectories.png`` and
    ``errors.png``)."""
    r, s, m, u = data["route"], data["summary"], data["map"], data["uwb"]
    blocked = ", ".join(
        f"{100 * b / max(u['exchanges'] / len(u['blocked_per_anchor']), 1):.0f} %"
        for b in u["blocked_per_anchor"]
    )
    lines = [
        "# Chapter 6 in the twin: localisation architectures compared (fig. 6.8)",
        "",
        f"Route `{r['name']}` in world `{r['world']}`: {r['length_m']:.1f} m driven at up to "
        f"{r['max_speed_m_s']:.1f} m/s in {data['sim_s']:.1f} simulated s (wall time "
        f"{data['drive_wall_s']:.1f} s "
        f"for the drive, {data['wall_s']:.1f} s in all); goal reached: "
        f"{'yes' if r['reached_goal'] else 'NO'}; "
        f"cross-track RMS {r['cross_track_rms_m']:.3f} m. Firmware `{data['firmware']}`, seed "
        f"{data['seed']}. "
        "Messages: "
        + ", ".join(f"{k} {v}" for k, v in data["messages"].items())
        + ". UWB exchanges with a "
        f"wall in the line, per anchor: {blocked}.",
        "",
        robot_line(data["robot"]),
        "",
        "| architecture | ATE m | ATE aligned m | RPE m / 1 m | RPE deg / 1 m | final position "
        "error m "
        "| final heading error deg | RMS heading error deg | max heading error deg | compute s |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    for name, e in data["architectures"].items():
        lines.append(
            f"| {name} | {e['ate_m']:.3f} | {e['ate_aligned_m']:.3f} | {e['rpe_trans_m']:.3f} | "
            f"{e['rpe_rot_deg']:.2f} | {e['final_pos_err_m']:.3f} | {e['final_yaw_err_deg']:.2f} | "
            f"{e['rms_yaw_err_deg']:.2f} | {e['max_yaw_err_deg']:.2f} | {e['wall_s']:.2f} |"
        )
    lines += [
        "",
        *DEFINITIONS,
        "",
        "Trajectories (TUM: `timestamp tx ty tz qx qy qz qw`, map frame): `truth.tum` and "
        + ", ".join(f"`{e['tum']}`" for e in data["architectures"].values())
        + ". Reproduce a row with [evo](https://github.com/MichaelGrupp/evo), e.g. for "
        "odom+uwb+imu: " + "; ".join(f"`{c}`" for c in evo_commands(".")) + ".",
        "",
    ]
    if figures:
        lines += ["![trajectories](trajectories.png)", "", "![errors](errors.png)", ""]
    lines += [
        "## Checks",
        "",
        f"- Raw odometry drift: {s['odom_drift_final_m']:.3f} m at the end of the route "
        f"({s['odom_drift_pct_of_length']:.2f} % of the distance).",
        f"- Odometry + IMU against odometry alone on heading: {_yaw(data, 'odom+imu')} against "
        f"{_yaw(data, 'odom')}.",
        f"- LiDAR odometry ATE under {LIDAR_ATE_MAX_M:.2f} m: "
        f"{'yes' if s['lidar_ate_under_0_10_m'] else 'NO'} "
        f"({data['architectures']['odom+lidar']['ate_m']:.3f} m).",
        f"- Map: {m['occupied_cells']} occupied cells, {100 * m['within_tolerance_frac']:.1f} % "
        f"within "
        f"{m['tolerance_cells']} cells of the world's walls (95th percentile "
        f"{m['p95_distance_cells']:.2f} cells, "
        f"max {m['max_distance_cells']:.1f}); {100 * m['outline_seen_frac']:.0f} % of the "
        f"world's outline at "
        "LiDAR height is mapped (racks' far sides are never seen).",
        "",
        "![map](map.png)",
        "",
        "The map is a map_server YAML + PGM (`map.yaml`): `amr-twin run --world map.yaml` "
        "drives in it.",
        "",
    ]
    return "\n".join(lines)
