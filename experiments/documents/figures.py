"""The figures the documents quote, written by the code from the experiments' committed results.

After a change of the plant or the firmwares, one command regenerates them all:

    python -m amr_twin.experiments.documents.figures

It runs the fault study (``docs/reference/faults.md``, ``docs/img/faults_*.png``), the payload
sweep of ``docs/reference/results.md`` (``docs/img/sweep_angular.png``), the fusion experiment's
ten seeds on both routes (most of the command's few minutes) and the chapter 5 runs
(``tests/chapter5_scorecard.json``, ``docs/img/chapter5_run1.png``: the README's first-run picture)
and the chapter 5 attainability study (128 plants: a few minutes); each experiment's committed
data goes to its ``experiments/<name>/reference/`` folder, not to docs/. It
then rewrites the generated blocks of :data:`DOCUMENTS` (their texts: :mod:`.texts`,
:mod:`.chapter5_texts`) from those
committed files and the calibration's report (``models/amr/calibration.yaml``: after a new fit,
``amr-twin calibrate --no-fit --report models/amr/calibration.yaml`` first). A block is the text
between ``<!-- generated: NAME ... -->`` and ``<!-- end: NAME -->``;
:func:`expected` gives a document as its blocks would be written now, which the tests hold every
document to, and the tests hold the committed results to a fresh run (``test_faults_report``,
``test_chapter5_outcome``): the figures cannot drift from the code.
"""

from __future__ import annotations

import json
import re
from pathlib import Path

from amr_twin.experiments.chapter5.scorecard import SCORECARD
from amr_twin.experiments.chapter5.attainable import COMMITTED_JSON
from amr_twin.experiments.faults.report import COMMITTED_JSON as FAULTS_JSON, PAGE as FAULTS_PAGE
from amr_twin.experiments.documents.chapter5_texts import (
    attainable_table,
    chapter5_summary,
    chapter5_table,
)
from amr_twin.experiments.documents.texts import (
    SUMMARY_FUSION,
    calibration_summary,
    faults_summary,
    fusion_table,
    payload_summary,
)
from amr_twin.model.paths import ROOT

COMMAND = "python -m amr_twin.experiments.documents.figures"
CALIBRATION = ROOT / "models" / "amr" / "calibration.yaml"
DOCUMENTS = (
    ROOT / "docs" / "reference" / "results.md",
    ROOT / "docs" / "explanation" / "validation.md",
    ROOT / "docs" / "explanation" / "fusion.md",
)
"""The documents with generated blocks (``docs/reference/faults.md`` is generated whole; the
README has none: it links to ``docs/reference/results.md``)."""
_BLOCK = re.compile(
    r"(<!-- generated: (?P<name>[\w-]+) [^>]*-->\n)(?P<body>.*?)(<!-- end: (?P=name) -->)", re.S
)

PAYLOAD_SWEEP = {
    "masses": [0.0, 10.0, 20.0, 30.0, 40.0, 50.0, 60.0],
    "positions": ["center", "front", "rear", "front-left-corner"],
    "commands": ["linear:0.7", "angular:-60:-1"],
}
"""The payload sweep of ``docs/reference/results.md`` (``amr-twin sweep payload --masses 0:60:10
--positions center,front,rear,front-left-corner --commands linear:0.7,angular:-60:-1``), 8 s a
point."""
PAYLOAD_JSON = ROOT / "experiments" / "payload" / "reference" / "sweep.json"


def payload_figures(results: dict, improved: dict | None) -> dict:
    """What ``docs/reference/results.md`` quotes of the payload sweep (committed as
    :data:`PAYLOAD_JSON`)."""
    from amr_twin.experiments.payload.sweep_report import summarise

    summary = summarise(results)
    for position, entry in summarise(improved).items() if improved else ():
        summary[position]["improved"] = entry
    rows = results["rows"]
    low = min(
        (r for r in rows if r.get("dyn_min_wheel_n") is not None),
        key=lambda r: r["dyn_min_wheel_n"],
    )
    energy = {
        f"{r['mass_kg']:g}": r["energy_j_per_m"]
        for r in rows
        if r["position"] == "center" and r["command"] == "linear:0.7"
    }
    return {
        "sweep": PAYLOAD_SWEEP,
        "points": len(rows),
        "positions": summary,
        "lowest_wheel": {
            k: low.get(k)
            for k in (
                "mass_kg",
                "position",
                "command",
                "dyn_min_wheel_n",
                "dyn_min_wheel_mechanism",
            )
        },
        "max_tilt_deg": max(r["max_tilt_deg"] for r in rows if r.get("max_tilt_deg") is not None),
        "center_energy_j_per_m": energy,
    }


FUSION_ROUTES = ("warehouse_60m", "corridor")
FUSION_SEEDS = list(range(10))


def fusion_json(route: str) -> Path:
    """The committed summary of ``amr-twin experiment fusion --route ROUTE --seeds 0:9`` (no wall
    times)."""
    return ROOT / "experiments" / "fusion" / "reference" / f"{route}.json"


def blocks() -> dict[str, str]:
    """Every block's text, from the committed results."""
    import yaml

    card = json.loads(SCORECARD.read_text())
    return {
        "chapter5-summary": chapter5_summary(card),
        "chapter5-checks": chapter5_table(card),
        "faults-summary": faults_summary(json.loads(FAULTS_JSON.read_text())),
        "payload-summary": payload_summary(json.loads(PAYLOAD_JSON.read_text())),
        **{
            f"fusion-{r}-summary": fusion_table(
                json.loads(fusion_json(r).read_text()), SUMMARY_FUSION
            )
            for r in FUSION_ROUTES
        },
        **{
            f"fusion-{r}": fusion_table(json.loads(fusion_json(r).read_text()))
            for r in FUSION_ROUTES
        },
        "calibration-summary": calibration_summary(yaml.safe_load(CALIBRATION.read_text())),
        "chapter5-attainable": attainable_table(json.loads(COMMITTED_JSON.read_text())),
    }


def expected(path: Path, texts: dict[str, str] | None = None) -> str:
    """``path``'s text with each generated block as :func:`blocks` writes it (unknown names: an
    error)."""
    texts = blocks() if texts is None else texts

    def fill(m: re.Match) -> str:
        return m.group(1) + texts[m.group("name")] + m.group(4)

    return _BLOCK.sub(fill, Path(path).read_text())


def payload_figures_write(
    cfg,
) -> None:  # pragma: no cover - 56 points and the re-run, about a minute
    """Run :data:`PAYLOAD_SWEEP`, write :data:`PAYLOAD_JSON` and ``docs/img/sweep_angular.png``."""
    import shutil
    import tempfile

    from amr_twin.experiments.payload import (
        sweep as payload_sweep,
        sweep_report as payload_sweep_report,
    )
    from amr_twin.experiments.runner.executor import write_json

    with tempfile.TemporaryDirectory() as tmp:
        sweep = PAYLOAD_SWEEP
        results = payload_sweep.run(
            cfg, Path(tmp), sweep["masses"], sweep["positions"], sweep["commands"], jobs=2
        )
        improved = payload_sweep.improved_beside(cfg, Path(tmp), results, jobs=2)
        payload_sweep_report.plot(results, Path(tmp), improved)
        shutil.copyfile(
            Path(tmp) / "sweep_angular_-60_-1.png", ROOT / "docs" / "img" / "sweep_angular.png"
        )
    write_json(PAYLOAD_JSON, payload_figures(results, improved))


def fusion_write(cfg) -> None:  # pragma: no cover - 20 drives, minutes
    """Run the fusion experiment's seeds on both routes; write :func:`fusion_json` of each."""
    import tempfile

    from amr_twin.experiments.fusion import seeds as fusion_seeds
    from amr_twin.experiments.runner.executor import write_json

    for route in FUSION_ROUTES:
        results = fusion_seeds.run(
            cfg, ROOT / "experiments" / "routes" / f"{route}.yaml", FUSION_SEEDS, jobs=2
        )
        with tempfile.TemporaryDirectory() as tmp:
            data = fusion_seeds.write(results, Path(tmp))
        write_json(fusion_json(route), _without_wall_times(data))


def _without_wall_times(value):
    """``value`` without its ``wall_s`` entries (a measured time, not a result: the same code gives
    the same file)."""
    if isinstance(value, dict):
        return {k: _without_wall_times(v) for k, v in value.items() if k != "wall_s"}
    if isinstance(value, list):
        return [_without_wall_times(v) for v in value]
    return value


def main() -> None:  # pragma: no cover - rewrites the committed results and documents (minutes)
    from amr_twin.experiments.chapter5 import (
        experiment as chapter5,
        attainable as chapter5_attainable,
        scorecard as chapter5_scorecard,
    )
    from amr_twin.experiments.faults import experiment as faults, report as faults_report
    from amr_twin.experiments.runner.executor import write_text
    from amr_twin.model.config import load_config

    cfg = load_config()
    results = faults.run(cfg, jobs=2, progress=True)
    faults_report.committed_write(results)
    chapter5_scorecard.main()
    payload_figures_write(cfg)
    fusion_write(cfg)
    chapter5_attainable.committed_write(cfg)
    run1 = chapter5.run(cfg, runs=[1], progress=False)
    chapter5.plot(run1, ROOT / "docs" / "img")
    (ROOT / "docs" / "img" / "run1.png").replace(ROOT / "docs" / "img" / "chapter5_run1.png")
    texts = blocks()
    for path in DOCUMENTS:
        write_text(path, expected(path, texts))
    print(
        f"rewrote {FAULTS_PAGE.relative_to(ROOT)}, tests/chapter5_scorecard.json, "
        f"docs/img/chapter5_run1.png and the generated "
        f"blocks of {', '.join(str(p.relative_to(ROOT)) for p in DOCUMENTS)}"
    )


def parse_args(argv: list[str]) -> None:
    """The command takes no arguments: ``--help`` prints what it does; anything else is refused
    (exit 2) before any work (it ignored them, and ``--help`` started the minutes of rewriting)."""
    import argparse
    import sys

    parser = argparse.ArgumentParser(
        prog=COMMAND,
        description="Rewrite the figures the documents quote from fresh "
        "runs (docs/reference/faults.md, the payload sweep, fusion and chapter 5 results, the "
        "generated blocks of README.md, docs/explanation/validation.md, "
        "docs/explanation/fusion.md); several "
        "minutes.",
    )
    _, extra = parser.parse_known_args(argv)
    if extra:
        print(
            f"error: {COMMAND}: takes no arguments (got {' '.join(extra)}); see --help",
            file=sys.stderr,
        )
        raise SystemExit(2)


if __name__ == "__main__":  # pragma: no cover
    import sys

    parse_args(sys.argv[1:])
    main()
