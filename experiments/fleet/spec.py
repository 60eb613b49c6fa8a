"""The fleet experiment's spec: fleet sizes, payload mixes, seeds, the order rate and the
simulated duration, checked before any episode (docs/how-to/fleet.md, "How many AMRs").

:meth:`FleetSpec.validate` refuses bad input with a ValueError of one line naming the field (the
CLI's option), from Python as from ``amr-twin experiment fleet``; :func:`run` runs the episodes
(this process, a local pool or Dask) and writes the report.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

from amr_twin.experiments.fleet.result import EpisodePoint, EpisodeResult
from amr_twin.experiments.registry import EXPERIMENTS, Experiment

MAX_ROBOTS = 20
MAX_SEEDS = 1000
SEED_LIMIT = 2**32
MAX_DURATION_S = 86400.0
MAX_JOBS_PER_HOUR = 10000.0


@dataclass(frozen=True)
class FleetSpec:
    """Seeded order streams for fleets of the twin under the project's fleet manager.

    Args:
        robots: fleet sizes, each in [1, 20].
        payload_kg: payload mixes, each a (low, high) range of kg within [0, payload.max_mass_kg].
        seeds: the order streams' (and sensors') seeds, in [0, 2^32).
        duration_s: simulated seconds of each episode, (0, 86400].
        jobs_per_hour: mean arrival rate of orders (Poisson), (0, 10000].
        world: a world of models/worlds/ with rack faces and docks on its roadmap.
        near_miss_m: two robots' true centres closer than this are a near miss, m.
        charge_below: the manager sends a vehicle to charge below this batteryCharge, %.
    """

    robots: tuple[int, ...] = (1, 2, 4, 8)
    payload_kg: tuple[tuple[float, float], ...] = ((0.0, 30.0),)
    seeds: tuple[int, ...] = (0, 1, 2)
    duration_s: float = 600.0
    jobs_per_hour: float = 300.0
    world: str = "warehouse"
    near_miss_m: float = 1.2
    charge_below: float = 20.0

    def validate(self, max_payload_kg: float) -> list[EpisodePoint]:
        """Every check (ValueError, one line naming the field); the episodes, by payload mix,
        fleet size and seed."""
        from amr_twin.model.worlds import world_path

        sizes = tuple(self.robots)
        if (
            not sizes
            or len(set(sizes)) != len(sizes)
            or not all(isinstance(n, int) and 1 <= n <= MAX_ROBOTS for n in sizes)
        ):
            raise ValueError(
                f"--robots {_text(sizes)}: distinct whole numbers in [1, {MAX_ROBOTS}]"
            )
        for lo, hi in self.payload_kg or [(math.nan, math.nan)]:
            if not (0 <= lo <= hi <= max_payload_kg):
                raise ValueError(
                    f"--payload-kg {lo:g}-{hi:g}: LOW-HIGH with 0 <= LOW <= HIGH <= "
                    f"payload.max_mass_kg ({max_payload_kg:g} kg)"
                )
        seeds = tuple(self.seeds)
        if (
            not seeds
            or len(seeds) > MAX_SEEDS
            or len(set(seeds)) != len(seeds)
            or not all(isinstance(s, int) and 0 <= s < SEED_LIMIT for s in seeds)
        ):
            raise ValueError(
                f"--seeds {_text(seeds)}: at most {MAX_SEEDS} distinct whole numbers in [0, 2^32)"
            )
        if not (math.isfinite(self.duration_s) and 0 < self.duration_s <= MAX_DURATION_S):
            raise ValueError(f"--duration-s {self.duration_s:g}: must be in (0, 86400] s")
        if not (math.isfinite(self.jobs_per_hour) and 0 < self.jobs_per_hour <= MAX_JOBS_PER_HOUR):
            raise ValueError(f"--jobs-per-hour {self.jobs_per_hour:g}: must be in (0, 10000]")
        if not (math.isfinite(self.near_miss_m) and 0 < self.near_miss_m <= 10):
            raise ValueError(f"--near-miss-m {self.near_miss_m:g}: must be in (0, 10] m")
        if not (math.isfinite(self.charge_below) and 0 <= self.charge_below < 80):
            raise ValueError(f"--charge-below {self.charge_below:g}: must be in [0, 80) %")
        if not world_path(self.world).is_file():
            raise ValueError(f"--world {self.world}: not a world of models/worlds/ nor a file")
        return [
            EpisodePoint(
                n,
                (float(lo), float(hi)),
                s,
                float(self.duration_s),
                float(self.jobs_per_hour),
                self.world,
                float(self.near_miss_m),
                float(self.charge_below),
            )
            for lo, hi in self.payload_kg
            for n in sorted(sizes)
            for s in seeds
        ]


def _text(values) -> str:
    return ",".join(str(v) for v in values)


def _episode(item) -> EpisodeResult:
    """One episode in a worker: ``item`` is (cfg, point, record folder or None)."""
    from amr_twin.experiments.fleet.episode import run_episode

    cfg, point, record = item
    return run_episode(cfg, point, record)


def run(
    spec: FleetSpec,
    cfg,
    out_dir: Path,
    *,
    jobs: int = 1,
    client=None,
    progress=False,
    record: Path | None = None,
):
    """Validate ``spec``, run its episodes (``jobs`` local workers or a Dask ``client``) and write
    ``out_dir``'s report.md, metrics.json and plots; with ``record`` each episode's ``.mcap`` and
    ``.rrd`` there; the :class:`~amr_twin.experiments.fleet.report.FleetResult`."""
    from amr_twin.base.atomic_file import all_or_nothing
    from amr_twin.experiments.fleet import report
    from amr_twin.experiments.runner.executor import run_all

    points = spec.validate(cfg.payload.max_mass_kg)
    out_dir.mkdir(parents=True, exist_ok=True)
    if record is not None:
        from amr_twin.recording.rerun_capture import recording_folder

        record = recording_folder(record)  # absolute: a worker may run elsewhere
    items = [(cfg, p, record) for p in points]
    episodes = [
        r for _item, r in run_all(_episode, items, jobs, "fleet episodes", progress, client)
    ]
    order = {p: i for i, p in enumerate(points)}
    episodes.sort(key=lambda e: order[e.point])
    result = report.FleetResult(episodes)
    with all_or_nothing():
        report.write(result, cfg, out_dir)
    return result


EXPERIMENTS.register(
    "fleet",
    Experiment(
        "fleet",
        FleetSpec,
        run,
        EpisodeResult,
        "how many AMRs: orders per hour, lead times, utilisation, energy per order by fleet size",
    ),
)
