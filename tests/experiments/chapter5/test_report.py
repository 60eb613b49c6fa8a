"""report.md of chapter 5 (experiments/chapter5/report.py): it opens with the findings, then the
counts."""

import json
from pathlib import Path

import pytest

from amr_twin.experiments.chapter5 import experiment as chapter5
from amr_twin.experiments.chapter5.findings import (
    ATTAINABLE_COMMAND,
    ATTAINABLE_SECTION,
    VALIDATION_DOC,
    VALIDATION_SECTION,
    lines,
)
from amr_twin.experiments.chapter5.report import markdown
from amr_twin.model.config import load_config

ROOT = Path(__file__).resolve().parents[3]


@pytest.fixture(scope="module")
def written(tmp_path_factory):
    """Runs 1, 2, 3 and 7, 4 s each: every finding is judged but the duty's (no study, no run 5)."""
    out = tmp_path_factory.mktemp("ch5report")
    chapter5.report(
        chapter5.run(load_config(), runs=[1, 2, 3, 7], duration_s=4.0, progress=False), out
    )
    return json.loads((out / "metrics.json").read_text()), (out / "report.md").read_text()


def _top(report: str) -> str:
    """The block before the first paragraph of counts and definitions."""
    return report.split("\nFirmware: ")[0]


def test_the_report_opens_with_one_line_per_finding_then_the_counts(written):
    data, report = written
    top = _top(report)
    assert top.startswith(
        "# Chapter 5 step experiments: twin against thesis\n\n## What the twin reproduces"
    )
    expected = lines(data["findings"])
    assert [
        ln[2:] for ln in top.splitlines() if ln.startswith("- ")
    ] == expected  # every line, in order
    keys = [f["key"] for f in data["findings"]["findings"]]
    assert keys == ["overshoot_right", "tracking", "duty_raised", "oscillation", "timings"]
    for finding in data["findings"]["findings"]:
        assert (
            f"[{finding['verdict']}] {finding['claim']} ({finding['source']}): {finding['why']}"
            in top
        )
    assert top.index("- attainable checks passed") < top.index("- unattainable under listing 4.12")


def test_the_report_links_the_validation_page_whose_section_exists(written):
    _, report = written
    assert f"[{VALIDATION_DOC}]({VALIDATION_DOC})" in _top(report) and VALIDATION_SECTION in _top(
        report
    )
    assert f"## {VALIDATION_SECTION}" in (ROOT / VALIDATION_DOC).read_text()
    # and where the findings not reproduced are tried on every plant the ranges allow
    assert (
        ATTAINABLE_COMMAND in _top(report)
        and f"## {ATTAINABLE_SECTION}" in (ROOT / VALIDATION_DOC).read_text()
    )


def test_the_bound_table_marks_the_small_steps_out_of_reach(written):
    _, report = written
    small = "| 3 | left | 53.48 | 1.12 | 0.56 / 0.3 ✗ | 0.90 / 0.7 ✗ | 1.12 / 0.8 ✗ | 1.04 / 1.6 |"
    assert small in report
    assert (
        "| 1 | left | 76.39 | 0.79 | 0.39 / 0.7 | 0.63 / 1.3 | 0.79 / 1.4 | 0.74 / 1.6 |" in report
    )


def test_a_metrics_object_without_findings_still_makes_a_report(written):
    data, _ = written
    older = {k: v for k, v in data.items() if k != "findings"}
    assert "## What the twin reproduces" not in markdown(older) and "## Bands missed" in markdown(
        older
    )
