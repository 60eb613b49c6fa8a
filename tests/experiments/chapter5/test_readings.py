"""Readings of the published samples: where each puts the samples and the clock, and the timings it
gives."""

from __future__ import annotations

import numpy as np
import pytest

from amr_twin.experiments.chapter5 import readings as rd

FINAL = 54.0
PUB = np.array([[1.0, 40.0], [2.0, 56.0]] + [[float(t), FINAL] for t in range(3, 12)])


def test_each_reading_places_the_samples_and_the_clock():
    t, rpm, t0, initial = rd.samples_as_read(PUB, 0.0, "command")
    assert t0 == 0.0 and initial == 0.0 and t[0] == 1.0
    t, rpm, t0, initial = rd.samples_as_read(PUB, 0.0, "first_sample")
    assert t0 == 1.0 and initial is None
    t, rpm, t0, initial = rd.samples_as_read(PUB, 0.0, "mid_revolution")
    assert t[0] == pytest.approx(1.0 - 30.0 / 40.0) and t[1] == pytest.approx(2.0 - 30.0 / 56.0)
    with pytest.raises(
        ValueError, match="reading: 'rqt' must be one of command, first_sample, mid_revolution"
    ):
        rd.samples_as_read(PUB, 0.0, "rqt")


@pytest.mark.parametrize(
    "reading, delay_s",
    [
        ("command", 0.5 * FINAL / 40.0),  # (0, 0) to (1, 40)
        ("first_sample", (47.0 - 40.0) / 16.0),  # 40 -> 54 from t = 1
        ("mid_revolution", 0.25 * 0.5 * FINAL / 40.0),
    ],
)  # (0, 0) to (0.25, 40)
def test_the_delay_follows_the_reading(reading, delay_s):
    checks = rd.timings(PUB, 0.0, 53.47, "left", reading)
    assert set(checks) == set(rd.TIMINGS)
    assert checks["delay_s"]["twin"] == pytest.approx(delay_s, abs=0.02)


def test_a_reading_reproduces_only_when_every_timing_check_passes():
    ok = rd.ReadingScore("x", {m: 3 for m in rd.TIMINGS}, 3, {})
    short = rd.ReadingScore("x", {**{m: 3 for m in rd.TIMINGS}, "peak_s": 2}, 3, {})
    assert ok.reproduces and not short.reproduces


def test_the_section_lists_every_reading_beside_the_thesis():
    rows = [
        {
            "reading": r,
            "passed": {m: 1 for m in rd.TIMINGS},
            "checks": 2,
            "reproduces": False,
            "median_s": {m: {"small": 0.4, "large": None} for m in rd.TIMINGS},
        }
        for r in rd.READINGS
    ]
    text = "\n".join(rd.markdown(rows))
    assert "thesis (≤ 75 / > 75 RPM) | 0.2/0.5" in text and "1/2 (0.40/—)" in text
    assert all(f"| {r} |" in text for r in rd.READINGS)


def test_the_conclusion_names_the_readings_that_hold():
    def row(name, small, large, ok):
        return {
            "reading": name,
            "passed": {m: 1 for m in rd.TIMINGS},
            "checks": 1,
            "reproduces": ok,
            "median_s": {m: {"small": small, "large": large} for m in rd.TIMINGS},
        }

    text = "\n".join(
        rd.markdown([row("command", 1.2, 1.5, False), row("first_sample", 0.7, 0.4, True)])
    )
    assert "Reproduces every timing: first_sample." in text
    assert "as §5.1.3 says (the ramp's order): command." in text
    assert "Reproduces every timing: no reading." in "\n".join(
        rd.markdown([row("command", 1.2, 1.5, False)])
    )
