"""The fusion experiment over many seeds: run in parallel, every seed kept, each metric's spread.

``amr-twin experiment fusion --seeds 0:9`` drives the route once per seed (each seed draws
the sensors' noise and the robot's own errors, :mod:`.robot`) in a local process pool
or on a Dask cluster (:func:`amr_twin.experiments.runner.executor.run_all`), scores the five
architectures of each drive, and reports every metric as mean, standard deviation (n - 1)
and range over the seeds, next to the per-seed values. Nothing is left out: a seed whose
drive missed its goal is reported as such and counted in the spread.

:func:`run` returns the per-seed :class:`~.results.FusionResults` (without their recorded
messages); :func:`write` writes ``seed<N>/`` (that seed's report, metrics, map and TUM
trajectories), the summary ``report.md`` and ``metrics.json``, and ``seeds.png``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from amr_twin.model.config import TwinConfig
from amr_twin.experiments.fusion import experiment as fusion
from amr_twin.experiments.fusion.results import FusionResults, slim
from amr_twin.experiments.runner.executor import run_all, save_figure, write_json, write_text
from amr_twin.experiments.fusion.seeds_report import METRICS, markdown, seed_text

MAX_SEEDS = 1000


@dataclass(frozen=True)
class SeedJob:
    """One drive of the experiment (picklable: it goes to a pool worker or a Dask worker)."""

    cfg: TwinConfig
    route_path: str
    seed: int
    firmware: str
    robot_errors: bool = True


def run_seed(job: SeedJob) -> FusionResults:
    """Drive and score one seed; the recorded messages are dropped before the result travels
    back."""
    return slim(
        fusion.run(
            job.cfg,
            job.route_path,
            seed=job.seed,
            firmware=job.firmware,
            progress=False,
            robot_errors=job.robot_errors,
        )
    )


def parse_seeds(text: str) -> list[int]:
    """``--seeds``: ``A:B`` (both included), ``a,b,c`` or one seed; ValueError with a one-line
    reason."""
    text = text.strip()
    try:
        if ":" in text:
            lo, hi = (int(v) for v in text.split(":"))
            if (
                hi - lo + 1 > MAX_SEEDS
            ):  # counted before the list is made (0:10**12 would fill the memory)
                raise OverflowError(hi - lo + 1)
            seeds = list(range(lo, hi + 1))
        else:
            seeds = [int(v) for v in text.split(",") if v.strip()]
    except OverflowError as exc:
        raise ValueError(
            f"--seeds {text!r}: {exc.args[0]} seeds; at most {MAX_SEEDS} (each is a drive)"
        ) from None
    except ValueError:
        raise ValueError(
            f"--seeds {text!r}: expected A:B (both included), a,b,c or one seed, whole numbers"
        ) from None
    if not seeds:
        raise ValueError(f"--seeds {text!r}: names no seed (A:B needs A <= B)")
    if len(set(seeds)) != len(seeds):
        raise ValueError(f"--seeds {text!r}: a seed is named twice")
    if len(seeds) > MAX_SEEDS:
        raise ValueError(
            f"--seeds {text!r}: {len(seeds)} seeds; at most {MAX_SEEDS} (each is a drive)"
        )
    bad = [s for s in seeds if not 0 <= s < 2**32]
    if bad:
        raise ValueError(f"--seeds {text!r}: seed {bad[0]} must be in [0, 2^32)")
    return seeds


def run(
    cfg: TwinConfig,
    route_path: Path | str,
    seeds: list[int],
    *,
    firmware: str = "improved",
    robot_errors: bool = True,
    jobs: int = 1,
    client=None,
    progress: bool = True,
) -> list[FusionResults]:
    """Run every seed (``jobs`` local workers, or the Dask ``client``); results in the order of
    ``seeds``."""
    items = [SeedJob(cfg, str(route_path), int(s), firmware, robot_errors) for s in seeds]
    done = {
        item.seed: res
        for item, res in run_all(
            run_seed, items, jobs=jobs, description="fusion seeds", progress=progress, client=client
        )
    }
    return [done[s] for s in seeds]


def spread(values) -> dict:
    """``mean``, ``sd`` (n - 1; 0 for one value), ``min``, ``max`` of a list of numbers (NaN
    ignored)."""
    v = np.asarray([x for x in values if x is not None and math.isfinite(x)], dtype=float)
    if v.size == 0:
        return {"mean": None, "sd": None, "min": None, "max": None, "n": 0}
    return {
        "mean": float(v.mean()),
        "sd": float(v.std(ddof=1)) if v.size > 1 else 0.0,
        "min": float(v.min()),
        "max": float(v.max()),
        "n": int(v.size),
    }


def summarise(per_seed: list[dict]) -> dict:
    """The spread of every metric of every architecture over the seeds' ``metrics.json`` data."""
    names = list(per_seed[0]["architectures"])
    out = {
        name: {
            key: spread([d["architectures"][name][key] for d in per_seed]) for key, _, _ in METRICS
        }
        for name in names
    }
    for name in names:  # how often each architecture has the lowest ATE
        out[name]["best_ate_seeds"] = sum(
            1
            for d in per_seed
            if min(d["architectures"], key=lambda n: d["architectures"][n]["ate_m"]) == name
        )
    return out


def write(results: list[FusionResults], out: Path) -> dict:
    """Write each seed's folder, the summary and ``seeds.png`` into ``out``; return the summary's
    data."""
    from amr_twin.experiments.fusion import plot as fusion_plot, report as fusion_report

    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    per_seed = []
    for k, res in enumerate(results):
        folder = out / f"seed{res.seed}"
        if k == 0:
            fusion_plot.plot(res, folder)
        per_seed.append(fusion_report.report(res, folder, figures=k == 0).as_json())
    first = results[0]
    data = {
        "route": {key: per_seed[0]["route"][key] for key in ("name", "world", "max_speed_m_s")},
        "firmware": first.firmware,
        "seeds": [r.seed for r in results],
        "reached_goal": [d["route"]["reached_goal"] for d in per_seed],
        "length_m": spread([d["route"]["length_m"] for d in per_seed]),
        "sim_s": spread([d["sim_s"] for d in per_seed]),
        "wall_s": spread([d["wall_s"] for d in per_seed]),
        "map_within_tolerance_frac": spread([d["map"]["within_tolerance_frac"] for d in per_seed]),
        "uwb_blocked_frac": spread(
            [sum(d["uwb"]["blocked_per_anchor"]) / max(d["uwb"]["exchanges"], 1) for d in per_seed]
        ),
        "robot": [d.get("robot") for d in per_seed],
        "architectures": summarise(per_seed),
        "per_seed": [
            {"seed": d["seed"], "architectures": d["architectures"], "robot": d.get("robot")}
            for d in per_seed
        ],
    }
    write_json(out / "metrics.json", data)
    _plot(data, out / "seeds.png")
    write_text(out / "report.md", markdown(data))
    return data


def _plot(data: dict, path: Path) -> None:
    """Per architecture, each seed's ATE (plain and aligned) as a dot: the spread at a glance."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from amr_twin.experiments.fusion.plot import COLOURS

    names = list(data["architectures"])
    fig, axes = plt.subplots(1, 2, figsize=(12, 4.5), layout="constrained", sharey=True)
    for ax, key, title in zip(
        axes, ("ate_m", "ate_aligned_m"), ("ATE, no alignment", "ATE after SE(2) alignment")
    ):
        for i, name in enumerate(names):
            v = [d["architectures"][name][key] for d in data["per_seed"]]
            x = i + np.linspace(-0.15, 0.15, len(v))
            ax.plot(x, v, "o", color=COLOURS.get(name, "k"), ms=5)
            ax.plot([i - 0.25, i + 0.25], [np.mean(v)] * 2, "-", color="k", lw=1.5)
        ax.set_xticks(range(len(names)), names, rotation=20)
        ax.set_yscale("log")
        ax.set_title(f"{title} (black: mean)")
        ax.grid(alpha=0.3, which="both")
    axes[0].set_ylabel("m")
    fig.suptitle(
        f"Route `{data['route']['name']}`, seeds {seed_text(data['seeds'])}: one dot per seed"
    )
    save_figure(fig, path)
