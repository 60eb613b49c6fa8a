"""The chapter 5 scorecard: every check's twin value, committed, so that a change that makes
the twin worse against the thesis fails a test until the scorecard is updated on purpose.

``python -m amr_twin.experiments.chapter5.scorecard`` runs the eight runs (faithful
firmware, shipped parameters) and rewrites ``tests/chapter5_scorecard.json`` (the checks of the
published samples, which the report's verdict counts, and of the true speed against the same
bands, ``run<N>.<wheel>.true.<metric>``);
:func:`worse` lists what got worse between a committed scorecard and a new one.

A check's *miss* is its distance outside the thesis' band (0 inside); a value that
cannot be measured has an infinite miss. A check gets worse when its miss grows by
more than the tolerance of its unit (:data:`TOLERANCE`).
"""

from __future__ import annotations

import json
import math
from pathlib import Path

from amr_twin.model.paths import ROOT

SCORECARD = ROOT / "tests" / "chapter5_scorecard.json"
TOLERANCE = {"s": 0.05, "RPM": 0.5}


def _unit(metric: str) -> str:
    return "s" if metric.endswith("_s") else "RPM"


def scorecard(data: dict) -> dict:
    """The scorecard of a chapter 5 ``metrics.json`` object: checks, comparisons, duties."""
    checks = {}
    for r in data["runs"]:
        for wheel, w in r["wheels"].items():
            for kind, prefix in (("checks", ""), ("true_checks", "true.")):
                for metric, c in w[kind].items():
                    checks[f"run{r['run']}.{wheel}.{prefix}{metric}"] = {
                        "twin": c["twin"],
                        "band": c["band"],
                        "thesis": c["thesis"],
                        "unit": _unit(metric),
                    }
    overshoot = {
        f"run{r['run']}.{wheel}": (w["published"] or {}).get("overshoot")
        for r in data["runs"]
        for wheel, w in r["wheels"].items()
    }
    s = data["summary"]
    return {
        "firmware": data["firmware"],
        "passed": s["passed"],
        "checks_total": s["checks"],
        "true_passed": s["true_passed"],
        "true_checks_total": s["true_checks"],
        "checks": checks,
        "published_overshoot_rpm": overshoot,
        "oscillation_published_passed": data["oscillation_verdict"]["published_passed"],
        "duty_raised_with_20kg": [c["raised"] for c in data.get("payload_duty", [])],
    }


def miss(value, band) -> float:
    """Distance of ``value`` outside ``band`` (0 inside; inf when not measured)."""
    if value is None or not math.isfinite(value):
        return math.inf
    lo, hi = band
    return max(0.0, lo - value, value - hi)


def worse(committed: dict, new: dict) -> list[str]:
    """The checks of ``new`` that are further outside their band than in ``committed``."""
    out = []
    for key, old in committed["checks"].items():
        now = new["checks"].get(key)
        if now is None:
            out.append(f"{key}: no longer measured")
            continue
        before, after = miss(old["twin"], old["band"]), miss(now["twin"], now["band"])
        if after > before + TOLERANCE[old["unit"]]:
            out.append(
                f"{key}: {now['twin']} misses its band {now['band']} by {after:.3g} {old['unit']} "
                f"(committed {old['twin']}, {before:.3g})"
            )
    for key, what in (("passed", "checks passed"), ("true_passed", "true-speed checks passed")):
        if new.get(key, 0) < committed.get(key, 0):
            out.append(f"{what}: {new[key]} < {committed[key]} committed")
    return out


def main() -> None:  # pragma: no cover - writes the committed file
    import tempfile

    from amr_twin.model.config import load_config
    from amr_twin.experiments.chapter5 import experiment as chapter5

    results = chapter5.run(load_config(), jobs=2, progress=True, study=False)
    data = chapter5.report(results, Path(tempfile.mkdtemp())).as_json()
    SCORECARD.write_text(json.dumps(scorecard(data), indent=1, sort_keys=True) + "\n")
    print(f"wrote {SCORECARD}: {data['summary']['passed']}/{data['summary']['checks']} checks pass")


if __name__ == "__main__":  # pragma: no cover
    main()
