"""UMBmark's spec: the robots, the squares and the contact, checked before any square.

:meth:`UmbmarkSpec.validate` refuses bad input with a ValueError of one line naming the field (the
CLI's option), from Python as from ``amr-twin experiment umbmark``; :func:`run` drives and writes.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from amr_twin.experiments.fusion.seeds import parse_seeds
from amr_twin.experiments.registry import EXPERIMENTS, Experiment
from amr_twin.experiments.umbmark import report, seeds
from amr_twin.experiments.umbmark.seeds import MAX_RUNS
from amr_twin.experiments.umbmark.square import Profile
from amr_twin.model.config import TwinConfig, with_values
from amr_twin.model.yaml_file import read_yaml
from amr_twin.base.atomic_file import all_or_nothing

RESERVED = ("wheel.tyre_slip", "sim.floor_friction_field")
"""Settings ``tyres`` and ``floor_field`` choose: a ``--set`` or ``--params`` of them is refused."""
_CHOSEN = "chosen by this command's --tyres/--no-tyres and --floor-field/--no-floor-field"


@dataclass(frozen=True)
class UmbmarkSpec:
    """UMBmark on many robots (Borenstein and Feng, 1996).

    Args:
        seeds: robots, ``A:B`` (both included), ``a,b,c`` or one seed (each draws its errors).
        runs: squares per direction and phase (Borenstein: 5), at most ``MAX_RUNS``.
        tyres: the brush tyres (the same robots also driven with the rigid contact) or the
            rigid contact only.
        floor_field: the floor's friction field, drawn per square.
    """

    seeds: str = "0:9"
    runs: int = 5
    tyres: bool = True
    floor_field: bool = True

    def validate(self, sets: list[str] = (), params: Path | None = None) -> list[int]:
        """Every check (ValueError, one line naming the field); the seeds. ``sets`` (``key=value``)
        and the ``params`` file may not set what the spec chooses (:data:`RESERVED`)."""
        seed_list = parse_seeds(self.seeds)
        if not 1 <= self.runs <= MAX_RUNS:
            raise ValueError(
                f"--runs {self.runs}: must be in 1..{MAX_RUNS} (squares per direction "
                "and phase, ~1 s of CPU each)"
            )
        for item in sets:
            key = item.partition("=")[0].strip()
            if key in RESERVED:
                raise ValueError(f"--set {key}: {_CHOSEN}")
        if params is not None:
            _check_params(params)
        return seed_list

    def values(self) -> dict[str, bool]:
        """The settings the spec chooses, ``{"dotted.key": value}``."""
        return {"wheel.tyre_slip": self.tyres, "sim.floor_friction_field": self.floor_field}

    def squares(self, seeds: int) -> int:
        """Squares driven for ``seeds`` robots: each way, before and after; with tyres the rigid
        contact's too."""
        return seeds * self.runs * 2 * (3 if self.tyres else 2)


def _check_params(params: Path) -> None:
    tree = read_yaml(params, "--params", ValueError) if params.is_file() else None
    for key in RESERVED:
        section, name = key.split(".")
        if isinstance(tree, dict) and isinstance(tree.get(section), dict) and name in tree[section]:
            raise ValueError(f"--params {params}: {key} is {_CHOSEN}")


def run(
    spec: UmbmarkSpec, cfg: TwinConfig, out_dir: Path, jobs: int = 1, progress: bool = False
) -> dict:
    """Validate ``spec``, drive every robot's squares before and after its calibration (``jobs``
    worker processes) and write ``out_dir``'s report
    (:func:`amr_twin.experiments.umbmark.report.write`); its data."""
    seed_list = spec.validate()
    if any(_value(cfg, key) != value for key, value in spec.values().items()):
        cfg = with_values(cfg, spec.values())
    profile = Profile()
    main = [seeds.SeedJob(cfg, s, spec.runs, profile) for s in seed_list]
    rigid = (
        [
            seeds.SeedJob(
                with_values(cfg, {"wheel.tyre_slip": False}), s, spec.runs, profile, calibrate=False
            )
            for s in seed_list
        ]
        if spec.tyres
        else []
    )
    meta = {
        "seeds": seed_list,
        "runs": spec.runs,
        "tyres": spec.tyres,
        "floor_field": spec.floor_field,
        "side_m": profile.side_m,
        "profile": {k: getattr(profile, k) for k in profile.__dataclass_fields__},
        "firmware": "improved",
    }
    done = seeds.run(main + rigid, jobs=jobs, progress=progress)
    with all_or_nothing():
        return report.write(done[: len(main)], done[len(main) :] or None, cfg, meta, out_dir)


def _value(cfg: TwinConfig, key: str):
    section, name = key.split(".")
    return getattr(getattr(cfg, section), name)


EXPERIMENTS.register(
    "umbmark",
    Experiment(
        "umbmark",
        UmbmarkSpec,
        run,
        dict,
        "UMBmark's return errors per robot, its odometry calibration and the squares again",
    ),
)
