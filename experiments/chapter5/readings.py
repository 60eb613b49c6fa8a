"""Readings of the published samples by which the thesis may have timed its plots, each scored.

§5.1.3 gives delay, rise, peak and settling times read off rqt_plot's lines of ``wheel0_Vel`` /
``wheel1_Vel``, which listing 4.12 publishes once per wheel revolution. How the author timed them is
not said. Each :data:`READINGS` entry is one explicit hypothesis, applied to the same published
samples of every run and judged against the same bands (:func:`.criteria.judge`):

- ``command``: the step at the command, the wheel at rest until the first sample, the samples joined
  by straight lines (the report's own reading);
- ``first_sample``: the clock started at the first published sample and the step measured from its
  value to the final one (what a reader sees when the plot begins where the topic begins);
- ``mid_revolution``: each sample placed at the middle of the revolution it averages (60 / rpm / 2 s
  before its arrival), from rest at the command (a reader who knows what a sample measures).

A reading reproduces the thesis' timings when every timing check it gives passes; the result is a
hypothesis with its evidence, not the score.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np

from amr_twin.analysis.metrics import step_info
from amr_twin.experiments.chapter5.criteria import TRANSIENT_WINDOW_S, judge, settling_band_rpm
from amr_twin.experiments.chapter5.timing_bound import TIMINGS as TIMING_BOUNDS

READINGS = ("command", "first_sample", "mid_revolution")
TIMINGS = tuple(TIMING_BOUNDS)  # delay, rise, peak, settling: the timings listing 4.12 bounds


@dataclass(frozen=True)
class ReadingScore:
    """One reading over all runs: per timing metric, checks passed of ``checks`` and the median
    twin value of each step class (``small``: <= 75 RPM, ``large``), s (None: never measured)."""

    reading: str
    passed: dict[str, int]
    checks: int
    median_s: dict[str, dict[str, float | None]]

    @property
    def reproduces(self) -> bool:
        return all(n == self.checks for n in self.passed.values())


def samples_as_read(
    pub: np.ndarray, t_command_s: float, reading: str
) -> tuple[np.ndarray, np.ndarray, float, float | None]:
    """``(t_s, rpm, t0_s, initial_value)`` of the published ``(k, 2)`` samples under ``reading``."""
    t, rpm = pub[:, 0], np.abs(pub[:, 1])
    if reading == "command":
        return t, rpm, t_command_s, 0.0
    if reading == "first_sample":
        return t, rpm, float(t[0]), None
    if reading == "mid_revolution":
        half = np.where(rpm > 0, 30.0 / np.maximum(rpm, 1e-9), 0.0)
        return np.maximum(t - half, t_command_s), rpm, t_command_s, 0.0
    raise ValueError(f"reading: {reading!r} must be one of {', '.join(READINGS)}")


def timings(
    pub: np.ndarray, t_command_s: float, reference_rpm: float, wheel: str, reading: str
) -> dict:
    """The timing checks (:func:`.criteria.judge`) of one wheel's samples under ``reading``."""
    if len(pub) < 2:
        return {}
    t, rpm, t0, initial = samples_as_read(pub, t_command_s, reading)
    info = step_info(
        t,
        rpm,
        abs(reference_rpm),
        t0_s=t0,
        initial_value=initial,
        settling_band=settling_band_rpm(reference_rpm),
        oscillation_window_s=TRANSIENT_WINDOW_S,
    )
    checks = judge(wheel, reference_rpm, info.as_dict(1.0))
    return {k: v for k, v in checks.items() if k in TIMINGS}


def score(runs: list[dict], reading: str) -> ReadingScore:
    """``reading`` over the analysed runs of :func:`.experiment.run` (each with its ``raw``
    series)."""
    passed = {m: 0 for m in TIMINGS}
    values: dict[str, dict[str, list[float]]] = {m: {"small": [], "large": []} for m in TIMINGS}
    checks = 0
    for r in runs:
        raw = r["raw"]
        for name, wheel in r["wheels"].items():
            index = 0 if name == "left" else 1
            found = timings(
                raw["published"][index], raw["t_command_s"], wheel["reference_rpm"], name, reading
            )
            checks += 1
            for m in TIMINGS:
                c = found.get(m)
                if c is None:
                    continue
                passed[m] += c["verdict"] == "pass"
                if c["twin"] is not None and math.isfinite(c["twin"]):
                    values[m][wheel["step_class"]].append(c["twin"])
    median = {
        m: {k: (float(np.median(v)) if v else None) for k, v in cls.items()}
        for m, cls in values.items()
    }
    return ReadingScore(reading, passed, checks, median)


def readings(results: dict) -> list[dict]:
    """Every reading's score over ``results["runs"]`` (JSON-ready, with ``reproduces``)."""
    out = []
    for reading in READINGS:
        s = score(results["runs"], reading)
        out.append({**asdict(s), "reproduces": s.reproduces})
    return out


def markdown(rows: list[dict]) -> list[str]:
    """The report's section: one row per reading, the thesis' values beside the medians."""

    def cell(m: str, row: dict) -> str:
        med = row["median_s"][m]
        text = "/".join("—" if med[k] is None else f"{med[k]:.2f}" for k in ("small", "large"))
        return f"{row['passed'][m]}/{row['checks']} ({text})"

    lines = [
        "| reading | delay s | rise s | peak s | settling s | reproduces |",
        "|---|---|---|---|---|---|",
        "| thesis (≤ 75 / > 75 RPM) | 0.2/0.5 | 0.5/1.0 | 0.6/1.1 | ≤ 1.3 | |",
    ]
    for row in rows:
        lines.append(
            f"| {row['reading']} | "
            + " | ".join(cell(m, row) for m in TIMINGS)
            + f" | {'yes' if row['reproduces'] else 'no'} |"
        )
    lines += [
        "",
        "Each cell: checks passed of the driven wheels, then the median twin value for steps of "
        "at most "
        "75 RPM / above. A reading is a hypothesis about how §5.1.3 was timed, not the score.",
        "",
    ]
    found = [row["reading"] for row in rows if row["reproduces"]]
    ordered = [row["reading"] for row in rows if slower_for_larger_steps(row)]
    lines.append(
        f"Reproduces every timing: {', '.join(found) or 'no reading'}. Larger steps slower in "
        f"delay, rise "
        f"and peak, as §5.1.3 says (the ramp's order): {', '.join(ordered) or 'no reading'}."
    )
    return lines


def slower_for_larger_steps(row: dict) -> bool:
    """Whether the reading's medians order delay, rise and peak as §5.1.3 does: above 75 RPM
    slower."""
    med = row["median_s"]
    return all(
        med[m]["small"] is not None
        and med[m]["large"] is not None
        and med[m]["large"] > med[m]["small"]
        for m in ("delay_s", "rise_s", "peak_s")
    )
