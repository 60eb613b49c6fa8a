"""The navigation experiment's spec: the episodes, the world, the maps and the people, checked
before any episode.

:meth:`NavigationSpec.validate` refuses bad input with a ValueError of one line naming the field
(the CLI's option), from Python as from ``amr-twin experiment navigation``; :func:`run` drives
and writes.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

from amr_twin.experiments.navigation.result import HallsResult, NavigationResult
from amr_twin.experiments.registry import EXPERIMENTS, Experiment
from amr_twin.model.config import TwinConfig

MAX_EPISODES = 1000
EPISODE_SIM_S = 70.0
"""Simulated time of a typical episode, s: the median time to the goal of the 50 episodes in
docs/explanation/navigation.md was 56-98 s by scenario (66 s on the true map, 74 s on the SLAM
map)."""
MAX_HALLS = 1000
SEED_LIMIT = 2**32
PEOPLE = ("static", "walking", "crossing", "none")


@dataclass(frozen=True)
class NavigationPlan:
    """What a validated spec runs.

    Args:
        halls: the generated halls (their names), or None: ``world`` is not one.
        tuning: the halls tuned on (reported apart from the held-out ones).
        maps: the maps each episode runs on (``true``, ``slam``).
    """

    halls: list[str] | None
    tuning: list[str] = field(default_factory=list)
    maps: tuple[str, ...] = ("true",)

    def places(self) -> int:
        """The halls or maps each episode runs on."""
        return len(self.halls) if self.halls else len(self.maps)


@dataclass(frozen=True)
class NavigationSpec:
    """Seeded start/goal episodes on the true and the SLAM map (docs/explanation/navigation.md).

    Args:
        episodes: start/goal pairs, each run on every map, in [1, ``MAX_EPISODES``].
        seed: the episodes' seed (episode i: ``default_rng([seed, i])``), in [0, 2^32).
        world: a world of models/worlds/, a ROS map .yaml or a generated hall
            ``generated:SEED[?door=W]``.
        generated_seeds: run on the generated halls of these seeds (``A-B`` or ``A,B,C``).
        tuning_seeds: the generated halls tuned on (``A-B``, ``A,B,C`` or ``none``).
        door_m: every doorway of the generated halls this wide, m.
        maps: ``true``, ``slam`` or ``true,slam`` (None: ``true`` on halls, else both).
        slam_map: a map_server YAML used as the SLAM map instead of building one.
        people: static, walking, crossing or none.
        localisation: a localisation of :data:`amr_twin.navigation.registries.LOCALISATIONS`.
        controller: a controller of :data:`amr_twin.navigation.registries.CONTROLLERS`.
        firmware: the firmware the episodes run.
    """

    episodes: int = 50
    seed: int = 0
    world: str = "aisles"
    generated_seeds: str | None = None
    tuning_seeds: str = "0-4"
    door_m: float | None = None
    maps: str | None = None
    slam_map: Path | None = None
    people: str = "walking"
    localisation: str = "ekf"
    controller: str = "mppi"
    firmware: str = "improved"

    def validate(self) -> NavigationPlan:
        """Every check (ValueError, one line naming the field); the halls and maps to run."""
        from amr_twin.navigation.registries import CONTROLLERS, LOCALISATIONS

        if not 0 <= self.seed < SEED_LIMIT:
            raise ValueError(f"--seed {self.seed}: must be a whole number in [0, 2^32)")
        if not 1 <= self.episodes <= MAX_EPISODES:
            raise ValueError(f"--episodes {self.episodes}: must be in [1, {MAX_EPISODES}]")
        halls, tuning = self._halls()
        maps = self.maps or ("true" if halls else "true,slam")
        kinds = tuple(k.strip() for k in maps.split(","))
        if (
            not kinds
            or any(k not in ("true", "slam") for k in kinds)
            or len(set(kinds)) != len(kinds)
        ):
            raise ValueError(f"--maps {maps!r}: true, slam or true,slam")
        if self.people not in PEOPLE:
            raise ValueError(f"--people {self.people!r}: static, walking, crossing or none")
        if halls and kinds != ("true",):
            raise ValueError(
                f"--maps {maps}: a generated hall has no mapping drive to build a SLAM map from: "
                f"give --maps true"
            )
        for registry, name in ((LOCALISATIONS, self.localisation), (CONTROLLERS, self.controller)):
            registry.get(name)
        if not halls:
            self._check_world(kinds)
        self._check_slam_map(halls, kinds)
        return NavigationPlan(halls, tuning, kinds)

    def simulated_s(self, plan: NavigationPlan) -> float:
        """Simulated seconds of the episodes of ``plan``, estimated (:data:`EPISODE_SIM_S`)."""
        return self.episodes * plan.places() * EPISODE_SIM_S

    def _check_world(self, kinds: tuple[str, ...]) -> None:
        from amr_twin.model.occupancy_map import load_map
        from amr_twin.model.worlds import MapError, world_path

        path = world_path(self.world)
        if not path.is_file() or path.suffix.lower() not in (".xml", ".yaml", ".yml"):
            raise ValueError(
                f"--world {self.world}: not a world of models/worlds/, an MJCF .xml file nor a "
                "ROS map .yaml"
            )
        if path.suffix.lower() == ".xml":
            return
        try:
            load_map(path)
        except MapError as exc:
            raise ValueError(f"--world {exc}") from None
        if "slam" in kinds and self.slam_map is None:
            raise ValueError(
                f"--world {self.world}: a ROS map world has no mapping drive to build a SLAM map "
                "from: give --maps true or --slam-map"
            )

    def _check_slam_map(self, halls: list[str] | None, kinds: tuple[str, ...]) -> None:
        from amr_twin.experiments.navigation.map import mapping_route
        from amr_twin.model.occupancy_map import load_map
        from amr_twin.model.worlds import MapError

        if self.slam_map is not None and halls:
            raise ValueError("--slam-map: a generated hall runs on its true map only")
        if self.slam_map is not None:
            try:
                load_map(self.slam_map)
            except MapError as exc:
                raise ValueError(f"--slam-map {exc}") from None
        elif "slam" in kinds:
            mapping_route(self.world)

    def _halls(self) -> tuple[list[str] | None, list[str]]:
        """The generated halls to run on (None: ``world`` is not one) and the tuning ones."""
        from amr_twin.model.generated_world import GeneratedWorldError, is_generated, name, parse
        from amr_twin.model.world_generator import FORCED_DOOR_RANGE_M

        door_m = self.door_m
        if door_m is not None and self.generated_seeds is None:
            raise ValueError(
                "--door-m: only with --generated-seeds (one hall: --world generated:SEED?door=W)"
            )
        low, high = FORCED_DOOR_RANGE_M
        if door_m is not None and not low <= door_m <= high:
            raise ValueError(f"--door-m {door_m:g}: must be in [{low:g}, {high:g}] m")
        if self.generated_seeds is None and not is_generated(self.world):
            return None, []
        if self.generated_seeds is None:
            try:
                door_m = parse(self.world)[1]
            except GeneratedWorldError as exc:
                raise ValueError(str(exc)) from None
            halls = [self.world]
        else:
            halls = [name(s, door_m) for s in hall_seeds("--generated-seeds", self.generated_seeds)]
        return halls, [name(s, door_m) for s in hall_seeds("--tuning-seeds", self.tuning_seeds)]


def hall_seeds(option: str, text: str) -> list[int]:
    """``A-B`` or ``A,B,C`` (or ``none``) as a list of seeds; a ValueError naming ``option``."""
    from amr_twin.model.generated_world import MAX_SEED

    usage = (
        f"{option} {text}: expected A-B, A,B,C or none (integers in [0, {MAX_SEED}], at most "
        f"{MAX_HALLS})"
    )
    if text.strip() == "none":
        return []
    try:
        if "-" in text:
            a, b = (int(v) for v in text.split("-"))
            seeds = list(range(a, b + 1)) if 0 <= a <= b and b - a < MAX_HALLS else []
        else:
            seeds = [int(v) for v in text.split(",")]
    except ValueError:
        seeds = []
    if (
        not seeds
        or len(seeds) > MAX_HALLS
        or len(set(seeds)) != len(seeds)
        or not all(0 <= v <= MAX_SEED for v in seeds)
    ):
        raise ValueError(usage)
    return seeds


def run(
    spec: NavigationSpec,
    cfg: TwinConfig,
    out_dir: Path,
    *,
    jobs: int = 1,
    client=None,
    progress: bool = False,
) -> NavigationResult | HallsResult:
    """Validate ``spec``, run its episodes (``jobs`` workers or a Dask ``client``) and write
    ``out_dir``'s report, figures and maps; the result."""
    return drive(spec, spec.validate(), cfg, out_dir, jobs=jobs, client=client, progress=progress)


def drive(
    spec: NavigationSpec,
    plan: NavigationPlan,
    cfg: TwinConfig,
    out_dir: Path,
    *,
    jobs: int = 1,
    client=None,
    progress: bool = False,
) -> NavigationResult | HallsResult:
    """Run the validated ``spec``'s ``plan`` and write ``out_dir``
    (:mod:`amr_twin.experiments.navigation.report`, or per hall
    :mod:`amr_twin.experiments.navigation.generated_report`); the result."""
    from amr_twin.base.atomic_file import all_or_nothing
    from amr_twin.experiments.navigation import experiment as navigation
    from amr_twin.experiments.navigation import generated_report, report

    common = dict(
        seed=spec.seed,
        localisation=spec.localisation,
        controller=spec.controller,
        firmware=spec.firmware,
        jobs=jobs,
        client=client,
        progress=progress,
        people=spec.people,
    )
    out_dir.mkdir(parents=True, exist_ok=True)
    if plan.halls:
        halls = navigation.run_halls(cfg, plan.halls, plan.tuning, spec.episodes, **common)
        with all_or_nothing():
            generated_report.write_worlds(cfg, halls, out_dir)
            generated_report.report(halls.as_json(), out_dir)
        return halls
    result = navigation.run(
        cfg,
        spec.world,
        spec.episodes,
        maps=plan.maps,
        slam_yaml=None if spec.slam_map is None else str(spec.slam_map),
        slam_stem=out_dir / "slam_map",
        **common,
    )
    with all_or_nothing():
        report.plot(result.rows, result.static_maps, out_dir)
        report.report(result.as_json(), out_dir)
    return result


EXPERIMENTS.register(
    "navigation",
    Experiment(
        "navigation",
        NavigationSpec,
        run,
        NavigationResult,
        "seeded start/goal episodes on the true and the SLAM map, some with a person in the way",
    ),
)
