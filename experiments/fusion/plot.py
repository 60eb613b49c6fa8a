"""The fusion experiment's figures, the twin's own fig. 6.8: ``trajectories.png`` (the route, the
true path and the five estimates over the warehouse) and ``errors.png`` (position and heading error
against time)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from amr_twin.analysis import se2
from amr_twin.experiments.fusion.experiment import ARCHITECTURES
from amr_twin.experiments.fusion.results import FusionResults
from amr_twin.experiments.runner.executor import save_figure

COLOURS = {
    "odom": "tab:red",
    "odom+lidar": "tab:green",
    "odom+imu": "tab:orange",
    "odom+uwb": "tab:purple",
    "odom+uwb+imu": "tab:blue",
}


def _draw_world(ax, results: FusionResults) -> None:
    from matplotlib.patches import Rectangle
    from matplotlib.transforms import Affine2D

    b = results.boxes
    for (cx, cy), (hx, hy), yaw in zip(b.centre_xy_m, b.half_xy_m, b.yaw_rad):
        rect = Rectangle((-hx, -hy), 2 * hx, 2 * hy, color="0.75", lw=0)
        rect.set_transform(Affine2D().rotate(yaw).translate(cx, cy) + ax.transData)
        ax.add_patch(rect)


def plot(results: FusionResults, out: Path) -> list[Path]:
    """Write ``trajectories.png`` and ``errors.png`` into ``out``; return their paths."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    fig, ax = plt.subplots(figsize=(14, 7.5), layout="constrained")
    _draw_world(ax, results)
    route = np.vstack(
        [np.asarray(results.route.start_xy_yaw[:2])[None], results.route.waypoints_xy_m]
    )
    ax.plot(route[:, 0], route[:, 1], ":", color="0.4", lw=1, label="route")
    ax.plot(results.pose_true[:, 0], results.pose_true[:, 1], "k-", lw=2.2, label="true path")
    for name in ARCHITECTURES:
        est = results.estimates[name]
        e = est.errors
        ax.plot(
            est.pose[:, 0],
            est.pose[:, 1],
            "-",
            lw=1.1,
            color=COLOURS[name],
            label=f"{name}: ATE {e.ate_m:.3f} m, final {e.final_pos_err_m:.2f} m",
        )
    anchors = results.anchors_xy_m
    if anchors is not None and len(anchors):
        ax.plot(anchors[:, 0], anchors[:, 1], "^", color="tab:purple", ms=9, label="UWB anchors")
    ax.set_aspect("equal")
    ax.set_xlabel("x, m (map)")
    ax.set_ylabel("y, m (map)")
    ax.set_title(
        f"Fusion architectures on the {results.estimates['odom'].errors.length_m:.0f} m route "
        f"`{results.route.name}` (seed {results.seed}; grey: the world at LiDAR height)"
    )
    ax.legend(loc="center left", bbox_to_anchor=(1.01, 0.5), fontsize=8)
    paths = [out / "trajectories.png"]
    save_figure(fig, paths[0])

    fig, (ax_p, ax_y) = plt.subplots(2, 1, figsize=(10, 6.5), sharex=True, layout="constrained")
    for name in ARCHITECTURES:
        est = results.estimates[name]
        t, ep, ey = _errors_in_time(results, est)
        ax_p.plot(t, ep, color=COLOURS[name], lw=1, label=name)
        ax_y.plot(t, np.degrees(ey), color=COLOURS[name], lw=1, label=name)
    ax_p.set_ylabel("position error, m")
    ax_y.set_ylabel("heading error, deg")
    ax_y.set_xlabel("sim time, s")
    ax_p.legend(fontsize=8, ncol=3)
    ax_p.grid(alpha=0.3)
    ax_y.grid(alpha=0.3)
    paths.append(out / "errors.png")
    save_figure(fig, paths[1])
    return paths


def _errors_in_time(results: FusionResults, est) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    truth = se2.interpolate(results.t_true_s, results.pose_true, est.t_s).reshape(-1, 3)
    return (
        est.t_s,
        np.hypot(*(est.pose[:, :2] - truth[:, :2]).T),
        se2.wrap_rad(est.pose[:, 2] - truth[:, 2]),
    )
