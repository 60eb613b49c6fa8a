"""``amr-twin experiment fleet``: how many AMRs; fleets of the twin under the project's fleet
manager on seeded order streams (docs/how-to/fleet.md, "How many AMRs").

Every option is checked before the first episode (one line, exit 2): the lists, the payload
ranges against ``payload.max_mass_kg``, the duration, the rate, the executor, the output folder.
"""

from __future__ import annotations

from pathlib import Path
from typing import Optional

import typer

from amr_twin.cli.checks import JobsOpt, check_executor, check_outputs, dask_client
from amr_twin.cli.common import _config, _guard, fail
from amr_twin.cli.options import ConfigOpt, ParamsOpt, SetOpt


def whole_numbers(option: str, text: str) -> tuple[int, ...]:
    """``A-B`` or ``A,B,C`` as whole numbers; a one-line refusal naming ``option``."""
    try:
        if "-" in text and "," not in text:
            a, b = (int(v) for v in text.split("-"))
            values = tuple(range(a, b + 1)) if 0 <= a <= b and b - a < 1000 else ()
        else:
            values = tuple(int(v) for v in text.split(","))
    except ValueError:
        values = ()
    if not values:
        fail(f"{option} {text}: expected A-B or A,B,C (whole numbers)")
    return values


def payload_ranges(text: str) -> tuple[tuple[float, float], ...]:
    """``LOW-HIGH[,LOW-HIGH...]`` kg (a single ``KG``: that mass every order)."""
    out = []
    for part in text.split(","):
        bounds = part.split("-")
        try:
            lo, hi = (float(bounds[0]), float(bounds[-1])) if len(bounds) <= 2 else (None, None)
        except ValueError:
            lo = hi = None
        if lo is None:
            fail(f"--payload-kg {text}: expected LOW-HIGH kg, ',' between mixes (e.g. 0-30)")
        out.append((lo, hi))
    return tuple(out)


def fleet_experiment(
    out: Path = typer.Option(
        ..., "--out", help="Output folder: report.md, metrics.json, throughput.png, tracks_<N>.png."
    ),
    robots: str = typer.Option("1,2,4,8", "--robots", help="Fleet sizes (A,B,C or A-B), 1-20."),
    payload_kg: str = typer.Option(
        "0-30", "--payload-kg", help="Payload mixes: LOW-HIGH kg, ',' between mixes."
    ),
    seeds: str = typer.Option("0-2", "--seeds", help="Seeds of the order streams (A-B or A,B,C)."),
    duration_s: float = typer.Option(600.0, "--duration-s", help="Simulated seconds an episode."),
    jobs_per_hour: float = typer.Option(
        300.0, "--jobs-per-hour", help="Mean arrival rate of orders (Poisson), per hour."
    ),
    world: str = typer.Option("warehouse", "--world", help="A world with racks and docks."),
    near_miss_m: float = typer.Option(
        1.2, "--near-miss-m", help="Two robots' true centres closer than this: a near miss, m."
    ),
    charge_below: float = typer.Option(
        20.0, "--charge-below", help="The manager sends a vehicle to charge below this charge, %."
    ),
    jobs: Optional[int] = JobsOpt,
    executor: str = typer.Option(
        "local", "--executor", help="local (process pool of --jobs) or dask."
    ),
    scheduler: Optional[str] = typer.Option(None, "--scheduler", help="Dask scheduler address."),
    scheduler_timeout_s: float = typer.Option(5.0, "--scheduler-timeout-s"),
    progress: bool = typer.Option(True, "--progress/--no-progress", help="Progress bar on stderr."),
    record: Optional[Path] = typer.Option(
        None,
        "--record",
        help="Write each episode's .mcap and .rrd (every robot) into this folder: "
        "fleet_<N>r_<LOW>-<HIGH>kg_s<SEED>.{mcap,rrd}.",
    ),
    config: Optional[Path] = ConfigOpt,
    params: Optional[Path] = ParamsOpt,
    set_: Optional[list[str]] = SetOpt,
) -> None:
    """How many AMRs: orders per hour, lead times, utilisation, energy per order by fleet size."""
    import os

    from amr_twin.experiments.fleet.spec import FleetSpec, run

    spec = FleetSpec(
        whole_numbers("--robots", robots),
        payload_ranges(payload_kg),
        whole_numbers("--seeds", seeds),
        duration_s,
        jobs_per_hour,
        world,
        near_miss_m,
        charge_below,
    )
    cfg = _config(config, params, set_)
    try:
        spec.validate(cfg.payload.max_mass_kg)
    except ValueError as exc:
        fail(str(exc))
    if jobs is not None and jobs < 1:
        fail(f"--jobs {jobs}: must be >= 1")
    check_executor(executor, scheduler, fail)
    check_outputs(fail, folders={"--out": out, "--record": record})
    workers = jobs if jobs is not None else max(1, len(os.sched_getaffinity(0)))
    client = dask_client(scheduler, scheduler_timeout_s, fail) if executor == "dask" else None
    try:
        result = _guard(
            lambda: run(
                spec, cfg, out, jobs=workers, client=client, progress=progress, record=record
            )
        )
    finally:
        if client is not None:
            client.close()
    for mix in result.summary():
        lo, hi = mix["payload_kg"]
        for r in mix["by_fleet_size"]:
            typer.echo(
                f"{lo:g}-{hi:g} kg, {r['robots']:2d} robots: {r['orders_per_hour_median']} "
                f"orders/h, lead p95 {r['lead_time_p95_s_median']} s, collisions "
                f"{r['collisions']}, deadlocks {r['deadlocks']}, near misses {r['near_misses']}"
            )
        sizes = [r["robots"] for r in mix["by_fleet_size"]]
        sat = mix["saturates_at_robots"]
        typer.echo(
            f"{lo:g}-{hi:g} kg: "
            + (
                f"throughput saturates at {sat} robots"
                if sat is not None
                else "one fleet size: saturation not determined"
                if len(sizes) < 2
                else f"no saturation up to {max(sizes)} robots"
            )
        )
    typer.echo(f"wrote {out}/report.md, metrics.json, throughput.png, tracks_<N>.png")
