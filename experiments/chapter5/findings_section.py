"""The sections of chapter 5's ``report.md`` on the findings: the block it opens with
(:func:`opening`), the committed study of plants inside the sourced ranges (:func:`attainable`)
and listing 4.12's bound on each published timing (:func:`bound_table`)."""

from __future__ import annotations

from amr_twin.experiments.chapter5.findings import (
    ATTAINABLE_COMMAND,
    ATTAINABLE_SECTION,
    VALIDATION_DOC,
    VALIDATION_SECTION,
    lines,
)
from amr_twin.experiments.chapter5.timing_bound import TIMINGS
from amr_twin.experiments.documents.chapter5_texts import attainable_table


def opening(data: dict) -> list[str]:
    """The block the report opens with: the findings, the attainable and unattainable checks, the
    link."""
    found = data.get("findings")
    if found is None:
        return []
    return [
        "## What the twin reproduces (read this first)",
        "",
        *[f"- {line}" for line in lines(found)],
        "",
        f"Why, and how the bound is derived: [{VALIDATION_DOC}]({VALIDATION_DOC}) (the path is "
        f"relative "
        f'to the amr-twin repository\'s root), section "{VALIDATION_SECTION}". Whether any plant '
        f"inside the "
        f"sourced ranges meets the findings not reproduced: `{ATTAINABLE_COMMAND}`, the same "
        f"page, section "
        f'"{ATTAINABLE_SECTION}".',
        "",
    ]


def attainable(data: dict) -> list[str]:
    """The committed study of plants inside the sourced ranges, when it was drawn around this
    plant."""
    study = data.get("attainable")
    if study is None:
        return [
            f"The committed study (`experiments/chapter5/reference/attainable.json`) was drawn "
            f"around another "
            f"plant, firmware or run "
            f"set than this report's: `{ATTAINABLE_COMMAND} --samples 64 --seed 1` draws it for "
            f"this plant."
        ]
    return [
        f"Plants drawn uniformly inside the sourced ranges around this plant "
        f"(`{ATTAINABLE_COMMAND}`, "
        f"{VALIDATION_DOC}): per finding, in how many it holds.",
        "",
        *attainable_table(study).splitlines(),
    ]


def bound_table(data: dict) -> list[str]:
    """Listing 4.12's bound on each published timing, per run and wheel, against the band's upper
    end."""
    bounds = (data.get("findings") or {}).get("bounds")
    if not bounds:
        return []
    rows: dict[tuple, dict] = {}
    for b in bounds:
        rows.setdefault((b["run"], b["wheel"], b["reference_rpm"]), {})[b["metric"]] = b
    head = " | ".join(f"{m} ≥ / band ≤" for m in TIMINGS)
    lines_ = [
        "## Listing 4.12's bound on the published timings",
        "",
        "One speed per wheel revolution, each the mean over its revolution: no plant whose samples "
        "stay at or below the reference while they climb can bring a published timing below its "
        "bound (T = 60/|rpm|: delay 0.5 T, rise 0.8 T, peak T, settling T less the band's share). "
        "✗ marks a check out of reach of any such plant.",
        "",
        f"| run | wheel | ref RPM | T s | {head} |",
        "|" + "---|" * (4 + len(TIMINGS)),
    ]
    for (run, wheel, ref), by in rows.items():
        cells = " | ".join(
            "—"
            if m not in by
            else f"{by[m]['bound_s']:.2f} / {by[m]['band_high_s']:g}"
            + ("" if by[m]["attainable"] else " ✗")
            for m in TIMINGS
        )
        lines_.append(f"| {run} | {wheel} | {ref:.2f} | {60.0 / abs(ref):.2f} | {cells} |")
    return lines_ + [""]
