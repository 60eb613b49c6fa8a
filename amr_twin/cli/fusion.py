"""``amr-twin experiment fusion``: chapter 6's architectures on a route, one seed or many.

One seed (``--seed N``, default 0) writes the full report into ``--out``: tables,
figures, the map and the TUM trajectories. Many (``--seeds 0:9``) run in parallel
(``--jobs`` local workers, or ``--executor dask --scheduler ADDRESS``) and write the
summary (mean, sd and range of every metric) with one folder per seed. Every option is
checked, and the route and its world read, before the first drive.
"""

from __future__ import annotations

from pathlib import Path
from typing import Optional

import typer

from amr_twin.cli.checks import (
    JobsOpt,
    YesOpt,
    check_common,
    check_estimate,
    check_executor,
    check_memory,
    check_outputs,
    dask_client,
)
from amr_twin.cli.common import _config, _guard, checked, fail
from amr_twin.cli.options import ConfigOpt, ParamsOpt, SetOpt, firmware_option


def fusion(
    out: Path = typer.Option(
        ...,
        "--out",
        help="Output folder: report.md, metrics.json, PNGs, map, TUM "
        "trajectories (with --seeds: the summary and seed<N>/ per seed).",
    ),
    route: Optional[str] = typer.Option(
        None,
        "--route",
        help="A route of experiments/routes/ by name "
        "(warehouse_60m, the default; corridor) or a route YAML file.",
    ),
    seed: Optional[int] = typer.Option(
        None, "--seed", help="One seed: the sensors' noise and the robot's own errors (default 0)."
    ),
    seeds: Optional[str] = typer.Option(
        None,
        "--seeds",
        help="Many seeds, A:B (both included) or a,b,c: "
        "each metric's mean, sd and range over them.",
    ),
    jobs: Optional[int] = JobsOpt,
    executor: str = typer.Option(
        "local", "--executor", help="With --seeds: local (process pool of --jobs) or dask."
    ),
    scheduler: Optional[str] = typer.Option(
        None, "--scheduler", help="Dask scheduler address, e.g. tcp://127.0.0.1:8786."
    ),
    scheduler_timeout_s: float = typer.Option(
        5.0, "--scheduler-timeout-s", help="Give up reaching the Dask scheduler after this long, s."
    ),
    firmware: str = firmware_option("improved"),
    record: Optional[Path] = typer.Option(
        None, "--record", help="Also write the drive as a Rerun recording (.rrd; one seed only)."
    ),
    mcap: Optional[Path] = typer.Option(
        None, "--mcap", help="Also write the drive as ROS 2 messages (.mcap; one seed only)."
    ),
    robot_errors: bool = typer.Option(
        True,
        "--robot-errors/--no-robot-errors",
        help="Each seed also draws "
        "the robot's own errors (tyre radii, track, hall sensors) within their "
        "sourced tolerances; off: the robot is exactly as its odometry assumes.",
    ),
    progress: bool = typer.Option(True, "--progress/--no-progress", help="Progress bar on stderr."),
    yes: bool = YesOpt,
    config: Optional[Path] = ConfigOpt,
    params: Optional[Path] = ParamsOpt,
    set_: Optional[list[str]] = SetOpt,
) -> None:
    """Drive a route and compare raw odometry with the four fusion architectures of §6.2.2."""
    from amr_twin.experiments.fusion.experiment import drive_bound_s
    from amr_twin.experiments.fusion.spec import FusionSpec

    jobs, firmware = check_common(jobs, firmware, fail)
    spec = FusionSpec(route, seed, seeds, firmware, robot_errors)
    seed_list = checked(spec.seed_list)
    many = len(seed_list) > 1
    if many and (record is not None or mcap is not None):
        fail("--record/--mcap record one drive: use --seed N with them, not --seeds")
    check_executor(executor, scheduler, fail)
    loaded = checked(spec.load_route)
    check_outputs(fail, files={"--record": record, "--mcap": mcap}, folders={"--out": out})
    cfg = _config(config, params, set_)
    checked(spec.check_route, cfg, loaded)
    client = dask_client(scheduler, scheduler_timeout_s, fail) if executor == "dask" else None
    workers = 1 if not many else jobs if client is None else max(1, sum(client.nthreads().values()))
    try:
        # a drive keeps every sensor message for its estimators, as a recording does
        check_memory(
            drive_bound_s(loaded),
            fail,
            recorded=True,
            sensors=True,
            processes=workers if client is None else 1,
            what="each drive",
        )
        check_estimate(
            f"experiment fusion: {len(seed_list)} drive{'s' if many else ''} of "
            f"{spec.route_path().stem}",
            spec.drive_s(loaded) * len(seed_list),
            "fusion",
            workers,
            firmware,
            yes,
            fail,
        )
        if many:
            _many(spec, cfg, seed_list, jobs, client, progress, out, _guard)
        else:
            _one(spec, cfg, seed_list, progress, record, mcap, out, _guard)
    finally:
        if client is not None:
            client.close()


def _one(spec, cfg, seeds: list[int], progress: bool, record, mcap, out: Path, guard) -> None:
    from amr_twin.experiments.fusion.spec import drive

    data = guard(lambda: drive(spec, cfg, out, seeds, progress=progress, record=record, mcap=mcap))
    typer.echo(
        f"{'architecture':14s} {'ATE m':>7s} {'aligned':>8s} {'RPE m/m':>8s} {'RPE deg/m':>9s} "
        f"{'final m':>8s} {'RMS yaw deg':>11s}"
    )
    for name, a in data.architectures.items():
        e = a.errors
        typer.echo(
            f"{name:14s} {e.ate_m:7.3f} {a.ate_aligned_m:8.3f} {e.rpe_trans_m:8.3f} "
            f"{e.rpe_rot_deg:9.2f} {e.final_pos_err_m:8.3f} {e.rms_yaw_err_deg:11.2f}"
        )
    s, r = data.summary, data.route
    typer.echo(
        f"route {r.name} {r.length_m:.1f} m, goal "
        f"{'reached' if r.reached_goal else 'NOT reached'}; "
        f"odometry drift {s.odom_drift_final_m:.3f} m; map walls within 2 cells: "
        f"{100 * s.map_walls_within_2_cells_frac:.1f} %"
    )
    typer.echo(
        f"wall time {data.wall_s:.2f} s for {data.sim_s:.1f} simulated s; wrote {out}/report.md, "
        f"truth.tum and one .tum per architecture (evo_ape tum {out}/truth.tum {out}/odom.tum)"
    )


def _many(spec, cfg, seeds: list[int], jobs: int, client, progress: bool, out: Path, guard) -> None:
    import time

    from amr_twin.experiments.fusion.seeds_report import cell
    from amr_twin.experiments.fusion.spec import drive

    def work():
        t0 = time.perf_counter()
        return drive(
            spec, cfg, out, seeds, jobs=jobs, client=client, progress=progress
        ), time.perf_counter() - t0

    data, wall_s = guard(work)
    typer.echo(
        f"{'architecture':14s} {'ATE m, mean ± sd (range)':32s} {'aligned':32s} {'RPE m / 1 m':32s}"
    )
    for name, a in data["architectures"].items():
        typer.echo(
            f"{name:14s} {cell(a['ate_m'], 3):32s} {cell(a['ate_aligned_m'], 3):32s} "
            f"{cell(a['rpe_trans_m'], 3):32s}"
        )
    missed = [s for s, ok in zip(data["seeds"], data["reached_goal"]) if not ok]
    where = "dask" if client is not None else f"jobs {jobs}"
    typer.echo(
        f"route {data['route']['name']}, {len(seeds)} seeds; goal "
        + ("reached in all" if not missed else f"NOT reached with seeds {missed}")
        + f"; wall time {wall_s:.1f} s ({where}); wrote {out}/report.md, metrics.json, "
        f"seeds.png, seed<N>/"
    )
