"""``report.md`` of the fusion experiment over many seeds (data from :func:`.seeds.write`)."""

from __future__ import annotations

from amr_twin.experiments.fusion.report import DEFINITIONS, evo_commands, tum_name

METRICS = (
    ("ate_m", "ATE m", 3),
    ("ate_aligned_m", "ATE aligned m", 3),
    ("rpe_trans_m", "RPE m / 1 m", 3),
    ("rpe_rot_deg", "RPE deg / 1 m", 2),
    ("final_pos_err_m", "final position m", 3),
    ("rms_yaw_err_deg", "RMS heading deg", 2),
    ("max_yaw_err_deg", "max heading deg", 2),
)
"""(key in metrics.json, column title, decimals) of the summary table."""


def seed_text(seeds: list[int]) -> str:
    """``0-9`` for a run of consecutive seeds, else ``1, 4, 7``."""
    if len(seeds) > 2 and seeds == list(range(seeds[0], seeds[-1] + 1)):
        return f"{seeds[0]}-{seeds[-1]}"
    return ", ".join(str(s) for s in seeds)


def cell(s: dict, decimals: int) -> str:
    """``mean ± sd (min-max)`` of a :func:`~.seeds.spread`."""
    if s["mean"] is None:
        return "-"
    f = f"{{:.{decimals}f}}"
    return (
        f"{f.format(s['mean'])} ± {f.format(s['sd'])} ({f.format(s['min'])}-{f.format(s['max'])})"
    )


def percent(s: dict) -> dict:
    """A spread of fractions in percent."""
    return {k: v if k == "n" or v is None else 100.0 * v for k, v in s.items()}


def table(data: dict) -> list[str]:
    """The summary table: one row per architecture, each metric as mean ± sd (min-max)."""
    lines = [
        "| architecture | " + " | ".join(title for _, title, _ in METRICS) + " | lowest ATE |",
        "|---|" + "---|" * (len(METRICS) + 1),
    ]
    n = len(data["seeds"])
    for name, a in data["architectures"].items():
        lines.append(
            f"| {name} | "
            + " | ".join(cell(a[key], dec) for key, _, dec in METRICS)
            + f" | {a['best_ate_seeds']} of {n} |"
        )
    return lines


def per_seed_table(data: dict) -> list[str]:
    """Every seed's ATE (plain / aligned) per architecture, and the robot's drawn errors."""
    names = list(data["architectures"])
    robot = any(d.get("robot") for d in data["per_seed"])
    head = "| seed | " + " | ".join(f"{n} ATE / aligned m" for n in names)
    head += " | wheel radii left, right mm | track mm | gyro scale % |" if robot else " |"
    lines = [head, "|---|" + "---|" * (len(names) + (3 if robot else 0))]
    for d, goal in zip(data["per_seed"], data["reached_goal"]):
        row = f"| {d['seed']}{'' if goal else ' (goal NOT reached)'} | " + " | ".join(
            f"{d['architectures'][n]['ate_m']:.3f} / {d['architectures'][n]['ate_aligned_m']:.3f}"
            for n in names
        )
        if robot:
            r = d["robot"] or {}
            row += (
                f" | {1e3 * r.get('radius_error_left_m', 0):+.2f}, "
                f"{1e3 * r.get('radius_error_right_m', 0):+.2f} "
                f"| {1e3 * r.get('separation_error_m', 0):+.2f} | "
                f"{100 * r.get('gyro_scale_z', 0):+.2f} |"
            )
        else:
            row += " |"
        lines.append(row)
    return lines


def markdown(data: dict) -> str:
    """The summary report."""
    r, seeds = data["route"], data["seeds"]
    reached = sum(data["reached_goal"])
    first = seeds[0]
    lines = [
        "# Chapter 6 in the twin: localisation architectures over many seeds",
        "",
        f"Route `{r['name']}` in world `{r['world']}`, firmware `{data['firmware']}`, seeds "
        f"{seed_text(seeds)} "
        f"({len(seeds)} drives; goal reached in {reached} of them). Route length "
        f"{data['length_m']['mean']:.1f} m, "
        f"{data['sim_s']['mean']:.1f} simulated s and {data['wall_s']['mean']:.1f} s of wall "
        f"time per drive on "
        "average. Each seed draws the sensors' noise and the robot's own errors; every seed is "
        "in the table "
        "and in the spread.",
        "",
        "Each cell: mean ± standard deviation (lowest-highest) over the seeds.",
        "",
        *table(data),
        "",
        f"Map from the LiDAR odometry, occupied cells within 2 cells of the world's walls: "
        f"{cell(percent(data['map_within_tolerance_frac']), 1)} %. UWB exchanges with a wall in "
        f"the "
        f"tag-anchor line: {cell(percent(data['uwb_blocked_frac']), 1)} %.",
        "",
        *DEFINITIONS,
        "",
        "## Every seed",
        "",
        *per_seed_table(data),
        "",
        "![ATE per seed](seeds.png)",
        "",
        "`seed<N>/` holds each seed's report, `metrics.json`, map and TUM trajectories "
        "(`truth.tum`, "
        + ", ".join(f"`{tum_name(n)}`" for n in data["architectures"])
        + "); the figures of seed "
        f"{first} are in `seed{first}/`. Check any row with evo, e.g. "
        + "; ".join(f"`{c}`" for c in evo_commands(f"seed{first}")[:3])
        + ".",
        "",
        f"![trajectories, seed {first}](seed{first}/trajectories.png)",
        "",
    ]
    return "\n".join(lines)
