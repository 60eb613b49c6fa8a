"""The navigation experiment's outputs: ``metrics.json``, ``report.md``, the trajectories over each
map."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from amr_twin.experiments.runner.executor import save_figure, write_json, write_text

COLOURS = {"clear": "tab:blue", "person": "tab:green", "pallet_jack": "tab:orange"}


def plot(rows: list[dict], static_maps: dict, out: Path) -> list[Path]:
    """``trajectories_<map>.png``: every episode's true path (5 Hz samples joined) over that map."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.patches import Rectangle

    paths = []
    for kind, sm in static_maps.items():
        sel = [r for r in rows if r["map"] == kind]
        h, w = sm.shape
        extent = (
            sm.origin_xy_m[0],
            sm.origin_xy_m[0] + w * sm.resolution_m,
            sm.origin_xy_m[1],
            sm.origin_xy_m[1] + h * sm.resolution_m,
        )
        fig, ax = plt.subplots(figsize=(14, 6.5))
        img = np.where(sm.occupied, 0.0, np.where(sm.unknown, 0.75, 1.0))
        ax.imshow(
            img, origin="lower", extent=extent, cmap="gray", vmin=0, vmax=1, interpolation="nearest"
        )
        for r in sel:
            xy = np.asarray(r["trajectory"], float)
            colour = COLOURS[r["scenario"]] if r["success"] else "red"
            ax.plot(xy[:, 0], xy[:, 1], "-", color=colour, lw=0.8, alpha=0.8)
            ax.plot(xy[:, 0], xy[:, 1], ".", color=colour, ms=1.2, alpha=0.6)
            ax.plot(*r["start"][:2], "o", color=colour, ms=3)
            ax.plot(*r["goal"][:2], "x", color=colour, ms=5)
            if r.get("actor"):
                line = np.asarray(r["actor"]["waypoints_xy_m"], float)
                ax.plot(line[:, 0], line[:, 1], "-", color=COLOURS["person"], lw=3, alpha=0.6)
            ob = r["obstacle"]
            if ob is not None:
                L, W = ob["size_m"][0], ob["size_m"][1]
                c, s = math.cos(ob["yaw_rad"]), math.sin(ob["yaw_rad"])
                corner = (ob["x_m"] - c * L / 2 + s * W / 2, ob["y_m"] - s * L / 2 - c * W / 2)
                ax.add_patch(
                    Rectangle(
                        corner,
                        L,
                        W,
                        angle=math.degrees(ob["yaw_rad"]),
                        color=COLOURS[ob["kind"]],
                        alpha=0.7,
                    )
                )
        n_ok = sum(r["success"] for r in sel)
        ax.set_title(
            f"{len(sel)} episodes on the {kind} map ({Path(sm.source).name}): {n_ok} succeeded\n"
            "blue clear, green person, orange pallet jack (rectangles: the unmapped obstacles; "
            "walking "
            "people: their crossing line), red failed; o start, x goal; dots: the true pose at "
            "5 Hz",
            fontsize=10,
        )
        ax.set_xlabel("x, m (map)")
        ax.set_ylabel("y, m (map)")
        ax.set_aspect("equal")
        path = out / f"trajectories_{kind}.png"
        save_figure(fig, path)
        paths.append(path)
    return paths


def _fmt(value, digits=2, scale=1.0, suffix=""):
    if value is None:
        return "-"
    return f"{value * scale:.{digits}f}{suffix}"


def report(data: dict, out: Path) -> None:
    """Write ``metrics.json`` and ``report.md`` from the experiment's data."""
    write_json(out / "metrics.json", data)
    s = data["summary"]
    lines = [
        f"# Navigation experiment: {data['episodes']} episodes x {len(data['maps'])} maps",
        "",
        f"World `{data['world']}`, seed {data['seed']}, people `{data.get('people', 'static')}`, "
        f"localisation "
        f"`{data['localisation']}`, controller "
        f"`{data['controller']}`, firmware `{data['firmware']}`. Optimal length: "
        f"{data['optimal']}.",
        "",
        "| map / scenario | episodes | success | collisions | time s | BARN | travelled/optimal "
        "median (max) "
        "| min clearance m | person >= 0.3 m | plan ms p50/p95 | controller ms p50/p99 | "
        "recoveries /100 m "
        "| w sign changes last m |",
        "|" + "---|" * 13,
    ]
    for key, v in s.items():
        lines.append(
            f"| {key} | {v['episodes']} | {_fmt(v['success_rate'], 1, 100, ' %')} | "
            f"{v['collisions']} | "
            f"{_fmt(v['time_s_mean'], 1)} | {_fmt(v['barn_score_mean'], 3)} | "
            f"{_fmt(v['travelled_over_optimal_median'], 3)} "
            f"({_fmt(v['travelled_over_optimal_max'], 3)}) | "
            f"{_fmt(v['min_clearance_m'], 3)} | "
            f"{_fmt(v['person_clearance_ge_0_3_share'], 0, 100, ' %')} of "
            f"{v['person_crossings']} | "
            f"{_fmt(v['plan_ms_p50'], 1)} / {_fmt(v['plan_ms_p95'], 1)} | "
            f"{_fmt(v['controller_ms_p50'], 2)} / {_fmt(v['controller_ms_p99'], 2)} | "
            f"{_fmt(v['recoveries_per_100m'], 2)} | {_fmt(v['w_sign_changes_last_m_mean'], 2)} |"
        )
    lines += [
        "",
        "Final distance to the goal, p95 (success is judged by the truth): "
        + "; ".join(
            f"{key} true {_fmt(v.get('final_error_true_m_p95'), 3)} m, estimate "
            f"{_fmt(v.get('final_error_estimate_m_p95'), 3)} m"
            for key, v in s.items()
            if key.endswith("/all")
        )
        + ".",
    ]
    failed = [r for r in data["rows"] if not r["success"]]
    lines += ["", f"Failed episodes ({len(failed)}):", ""]
    lines += [
        f"- {r['map']} map, episode {r['index']} ({r['scenario']}): {r['status']}"
        f"{', ' + str(r['collisions']) + ' collision(s) with ' if r['collisions'] else ''}"
        f"{', '.join(r['collided_with']) if r['collisions'] else ''}"
        f"{': ' + r['reason'] if r['reason'] else ''}"
        for r in failed
    ] or ["- none"]
    if data.get("slam_map"):
        m = data["slam_map"]
        lines += [
            "",
            f"SLAM map: `{m['yaml']}` ({m.get('route', 'given')}); "
            f"walls within 2 cells of the world: "
            f"{_fmt(m.get('walls_within_2_cells_frac'), 1, 100, ' %')}.",
        ]
    lines += [
        "",
        f"Wall time {data['wall_s']:.0f} s, CPU {data['cpu_s']:.0f} s (all processes), "
        f"{data['jobs']} job(s).",
        "",
    ]
    lines += [f"![trajectories on the {k} map](trajectories_{k}.png)" for k in data["maps"]]
    write_text(out / "report.md", "\n".join(lines) + "\n")
