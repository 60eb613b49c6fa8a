"""The fusion experiment's spec: the route and the seeds, checked before any drive.

:meth:`FusionSpec.validate` refuses bad input with a ValueError of one line naming the field (the
CLI's option), from Python as from ``amr-twin experiment fusion``; :func:`run` drives and writes.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from amr_twin.controllers.route import Route, RouteError, load_route
from amr_twin.experiments.fusion import experiment as fusion
from amr_twin.experiments.fusion import (
    plot as fusion_plot,
    report as fusion_report,
    seeds as fusion_seeds,
)
from amr_twin.experiments.fusion.metrics import FusionMetrics
from amr_twin.experiments.registry import EXPERIMENTS, Experiment
from amr_twin.model.build import BuildError
from amr_twin.model.config import TwinConfig
from amr_twin.base.atomic_file import all_or_nothing

SEED_LIMIT = 2**32
"""Seeds are whole numbers in [0, 2^32), as the CLI takes them."""


@dataclass(frozen=True)
class FusionSpec:
    """Chapter 6's architectures on a route, one seed or many.

    Args:
        route: a route of ``experiments/routes/`` by name, a route YAML file, or None
            (warehouse_60m).
        seed: one seed (the sensors' noise and the robot's own errors); None with ``seeds``, else 0.
        seeds: many seeds, ``A:B`` (both included) or ``a,b,c``; not with ``seed``.
        firmware: the firmware the drives run.
        robot_errors: each seed also draws the robot's own errors (tyre radii, track, hall sensors).
    """

    route: str | None = None
    seed: int | None = None
    seeds: str | None = None
    firmware: str = "improved"
    robot_errors: bool = True

    def seed_list(self) -> list[int]:
        """The seeds to drive (ValueError naming ``--seed`` or ``--seeds``)."""
        if self.seed is not None and self.seeds is not None:
            raise ValueError("--seed and --seeds: give one of them")
        if self.seeds is not None:
            seeds = fusion_seeds.parse_seeds(self.seeds)
        else:
            seeds = [self.seed or 0]
        if self.seed is not None and not 0 <= self.seed < SEED_LIMIT:
            raise ValueError(f"--seed {self.seed}: must be a whole number in [0, 2^32)")
        return seeds

    def route_path(self) -> Path:
        """The route's file (:func:`amr_twin.experiments.fusion.experiment.route_file`)."""
        return fusion.route_file(self.route)

    def load_route(self) -> Route:
        """The route read and checked on its own (ValueError naming ``--route``)."""
        path = self.route_path()
        try:
            return load_route(path)
        except (RouteError, OSError) as exc:
            if path.exists() or self.route is None:
                raise ValueError(f"--route {self.route}: {exc}") from None
            known = ", ".join(fusion.route_names())
            raise ValueError(
                f"--route {self.route}: no such route file, nor a route of the twin ({known})"
            ) from None

    def check_route(self, cfg: TwinConfig, route: Route) -> None:
        """The drive's simulated time bounded, each point in its world's free space (ValueError)."""
        try:
            fusion.check_route(cfg, route)
        except (RouteError, BuildError) as exc:
            raise ValueError(f"--route {self.route_path()}: {exc}") from None

    def validate(self, cfg: TwinConfig) -> tuple[list[int], Route]:
        """Every check (ValueError, one line naming the field); the seeds and the route."""
        seeds = self.seed_list()
        route = self.load_route()
        self.check_route(cfg, route)
        return seeds, route

    def drive_s(self, route: Route) -> float:
        """Simulated seconds of a drive of ``route``: the rest, the route at its speed, the tail."""
        return fusion.REST_S + fusion.route_length_m(route) / route.max_speed_m_s + fusion.TAIL_S


def run(spec: FusionSpec, cfg: TwinConfig, out_dir: Path, **options) -> FusionMetrics | dict:
    """Validate ``spec``, then :func:`drive` (its keyword ``options``); one seed's metrics or many
    seeds' summary."""
    seeds, _ = spec.validate(cfg)
    return drive(spec, cfg, out_dir, seeds, **options)


def drive(
    spec: FusionSpec,
    cfg: TwinConfig,
    out_dir: Path,
    seeds: list[int],
    *,
    jobs: int = 1,
    client=None,
    progress: bool = False,
    record: Path | None = None,
    mcap: Path | None = None,
) -> FusionMetrics | dict:
    """Drive the validated ``spec``'s ``seeds`` and write ``out_dir``'s report: one seed's
    :class:`FusionMetrics` (with its optional Rerun / MCAP recording), or, with many seeds
    (``jobs`` workers or a Dask ``client``), the summary of
    :func:`amr_twin.experiments.fusion.seeds.write`."""
    route_path = spec.route_path()
    if len(seeds) > 1:
        results = fusion_seeds.run(
            cfg,
            route_path,
            seeds,
            firmware=spec.firmware,
            robot_errors=spec.robot_errors,
            jobs=jobs,
            client=client,
            progress=progress,
        )
        with all_or_nothing():
            return fusion_seeds.write(results, out_dir)
    results = fusion.run(
        cfg,
        route_path,
        seed=seeds[0],
        firmware=spec.firmware,
        progress=progress,
        rrd_path=record,
        mcap_path=mcap,
        robot_errors=spec.robot_errors,
    )
    with all_or_nothing():
        fusion_plot.plot(results, out_dir)
        return fusion_report.report(results, out_dir)


EXPERIMENTS.register(
    "fusion",
    Experiment(
        "fusion",
        FusionSpec,
        run,
        FusionMetrics,
        "raw odometry against chapter 6's four fusion architectures on a route",
    ),
)
