"""Payload sweep: step response, duty, support loads, tilt and slip against payload mass and
position.

One simulation per (mass, position, command) point, in the empty world; each
point's result is one JSON file ``runs/<key>.json`` written atomically, so a rerun
after an interruption only simulates the missing points (a file made with other
parameters, firmware or duration is redone). The commands of one payload are one work
item (:func:`by_payload`): their files are written when the last of them is done. A
position that puts the payload off the deck fails the configuration check and is
recorded as invalid.

The points (named positions, the parsers, keys and fingerprints) are in
:mod:`.point`; one point's simulation and when it is **safe** in
:mod:`.simulation`. The highest safe payload of a position is the largest
mass whose every lighter point (all commands) is safe.

Reasons and measurements: docs/reference/results.md#amr_twinexperimentspayloadsweep."""

from __future__ import annotations

import json
import time
from pathlib import Path

from amr_twin.model.config import TwinConfig
from amr_twin.experiments.payload.point import Point, parse_command
from amr_twin.experiments.payload.simulation import simulate_points


def run(
    cfg: TwinConfig,
    out_dir: Path,
    masses: list[float],
    positions: list[str],
    commands: list[str],
    duration_s: float = 8.0,
    jobs: int = 1,
    firmware: str = "faithful",
    progress: bool = True,
    client=None,
    record_dir: Path | None = None,
    mcap_dir: Path | None = None,
    draws=None,
    before=None,
) -> dict:
    """Simulate the missing points of the sweep (one file each) and return all rows.

    The points run in this process (``jobs=1``), in ``jobs`` local worker
    processes, or on the Dask cluster of ``client`` (a ``distributed.Client``,
    see :func:`~amr_twin.experiments.runner.dask_cluster.connect_dask`); either way each
    result comes back here and is written atomically as it arrives.

    ``record_dir`` / ``mcap_dir``: folders for one ``<key>.rrd`` / ``<key>.mcap``
    recording per point simulated now (points reused from ``runs/`` are not
    re-simulated for a missing recording; see the module notes).

    ``draws``: :class:`amr_twin.calibration.draws.Draws` of ``cfg``'s parameters; each point
    is also run with each drawn configuration (rows with ``sample`` and ``sample_id``, after
    the nominal rows).

    ``before(n)``: called with the number of points to simulate (those not done already), before
    the first is (the CLI's time estimate, which may stop the sweep there).

    Returns
    -------
    dict : ``{"rows": [...], "simulated": n, "reused": n, "recorded": n, "wall_s": s}``.
    """
    from amr_twin.experiments.runner.executor import run_all, write_json

    for c in commands:
        parse_command(c)
    runs_dir = Path(out_dir) / "runs"
    from amr_twin.recording.rerun_capture import recording_folder

    folders = {
        kind: recording_folder(folder)
        for kind, folder in (("rrd", record_dir), ("mcap", mcap_dir))
        if folder is not None
    }

    def make_point(m: float, p: str, c: str, sample: int | None = None) -> Point:
        extra = {} if sample is None else {"sample": sample, "sample_id": draws.sample_id(sample)}
        point_cfg = cfg if sample is None else configs[sample]
        key = Point(m, p, c, duration_s, firmware, point_cfg, **extra).key
        paths = {f"{kind}_path": str(folder / f"{key}.{kind}") for kind, folder in folders.items()}
        return Point(m, p, c, duration_s, firmware, point_cfg, **paths, **extra)

    configs = [draws.config(cfg, i) for i in range(len(draws))] if draws is not None else []
    points = [
        make_point(m, p, c, sample)
        for sample in [None, *range(len(configs))]
        for m in masses
        for p in positions
        for c in commands
    ]
    rows, todo = {}, []
    for point in points:
        path = runs_dir / f"{point.key}.json"
        try:
            row = json.loads(path.read_text())
        except (OSError, ValueError):
            row = None
        if row is not None and row.get("fingerprint") == point.fingerprint:
            rows[point.key] = row
        else:
            todo.append(point)
    if before is not None:
        before(len(todo))
    wall0 = time.perf_counter()
    done = set()
    work = [(p,) for p in todo] if client is not None else by_payload(todo, jobs)
    for group, group_rows in run_all(
        simulate_points, work, jobs, "payload sweep", progress, client=client, size=len
    ):
        for item, row in zip(group, group_rows):
            write_json(runs_dir / f"{item.key}.json", row)
            rows[item.key] = row
            done.add(item.key)
    recorded = sum(
        any((folder / f"{key}.{kind}").exists() for kind, folder in folders.items()) for key in done
    )
    return {
        "rows": [rows[p.key] for p in points],
        "simulated": len(todo),
        "reused": len(points) - len(todo),
        "recorded": recorded,
        "wall_s": time.perf_counter() - wall0,
        "duration_s": duration_s,
        "firmware": firmware,
        **({"draws": draws} if draws is not None else {}),
    }


def by_payload(points: list[Point], jobs: int = 1) -> list[tuple[Point, ...]]:
    """The points as work items: the commands of one payload (mass, position, drawn configuration)
    together, so that one process runs them and its second twin starts from the first's built and
    settled physics (:mod:`amr_twin.sim.settled_physics`) instead of building and settling again.

    Adjacent points only (the sweep lists each payload's commands one after the other); one point
    per item when that would leave fewer items than ``jobs`` processes (a small sweep stays
    parallel).
    """
    groups: list[list[Point]] = []
    for point in points:
        last = groups[-1][-1] if groups else None
        if (
            last is not None
            and last.cfg is point.cfg
            and (last.mass_kg, last.position, last.sample)
            == (point.mass_kg, point.position, point.sample)
        ):
            groups[-1].append(point)
        else:
            groups.append([point])
    if len(groups) < jobs:
        return [(p,) for p in points]
    return [tuple(g) for g in groups]


def improved_beside(
    cfg: TwinConfig, out_dir: Path, results: dict, jobs: int = 1, progress: bool = True, client=None
) -> dict | None:
    """The positions of a faithful-firmware sweep whose limit is a runaway (the firmware's: the
    wheels leave their references and the motor current follows;
    :func:`.limits.limit_causes`), run again with the improved firmware on the same
    masses and commands, into ``out_dir/improved`` (resumed like any sweep); None when there is
    none, or the sweep ran another firmware."""
    from amr_twin.experiments.payload.sweep_report import summarise

    if results["firmware"] != "faithful":
        return None
    rows = results["rows"]
    positions = [p for p, s in summarise(results).items() if "runaway" in s["causes"]]
    if not positions:
        return None
    masses = sorted({r["mass_kg"] for r in rows if r["position"] in positions})
    commands = list(dict.fromkeys(r["command"] for r in rows))
    return run(
        cfg,
        Path(out_dir) / "improved",
        masses,
        positions,
        commands,
        duration_s=results["duration_s"],
        jobs=jobs,
        firmware="improved",
        progress=progress,
        client=client,
    )
