"""One navigation episode as a worker's item (:class:`EpisodeRun`, picklable) and its drive,
measured as nav2 is (:func:`run_episode`); :mod:`.experiment` runs many.

Reasons and measurements: docs/explanation/navigation.md#amr_twinexperimentsnavigationexperiment."""

from __future__ import annotations

import time
from dataclasses import dataclass

from amr_twin.experiments.navigation.episodes import Episode


@dataclass(frozen=True)
class EpisodeRun:
    """A worker's item: an episode on one map, with what it needs to run."""

    cfg: object
    world: str
    episode: Episode
    map_kind: str
    slam_yaml: str | None
    localisation: str = "ekf"
    controller: str = "mppi"
    firmware: str = "improved"


def run_episode(item: EpisodeRun) -> dict:
    """Drive one episode and measure it (:func:`amr_twin.experiments.navigation.metrics.measure`; in
    a generated hall its doorways too,
    :func:`amr_twin.experiments.navigation.generated.door_metrics`)."""
    from amr_twin.experiments.navigation.metrics import measure
    from amr_twin.model.generated_world import is_generated
    from amr_twin.navigation.navigation_run import navigate
    from amr_twin.navigation.stack import NavigationOptions
    from amr_twin.assembly.twin import TwinOptions

    ep = item.episode
    obstacles = () if ep.obstacle is None else (ep.obstacle,)
    twin_options = TwinOptions(
        firmware=item.firmware,
        world=item.world,
        seed=ep.seed * 100_003 + ep.index,
        start_xy_yaw=ep.start,
        visuals=False,
        obstacles=obstacles,
        actors=() if ep.actor is None else (ep.actor,),
    )
    options = NavigationOptions(
        goals=(ep.goal,),
        map_yaml=item.slam_yaml if item.map_kind == "slam" else None,
        localisation=item.localisation,
        controller=item.controller,
        seed=ep.seed * 100_003 + ep.index,
    )
    run = navigate(item.cfg, twin_options, options)
    row = measure(item.cfg, item.world, ep, item.map_kind, run)
    if is_generated(item.world):
        from amr_twin.experiments.navigation.generated import door_metrics

        row.update(world=item.world, **door_metrics(item.cfg, item.world, ep, run))
    return row


def timed_episode(item: EpisodeRun) -> dict:
    """:func:`run_episode`, its row with the process's CPU seconds it took (``cpu_s``)."""
    t0 = time.process_time()
    row = run_episode(item)
    row["cpu_s"] = time.process_time() - t0
    return row
