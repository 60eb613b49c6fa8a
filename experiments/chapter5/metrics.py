"""The chapter 5 metrics as typed records, and ``metrics.json`` written from them.

:func:`metrics` turns the results of :func:`amr_twin.experiments.chapter5.experiment.run` into a
:class:`Chapter5Metrics`: each run's measured step (:class:`RunMetrics`, :class:`WheelMetrics`),
each banded metric judged against the thesis (:class:`Check`), the loaded against unloaded
oscillation (:class:`OscillationComparison`) and the counts (:class:`CheckCount`).
:meth:`Chapter5Metrics.as_json` is the ``metrics.json`` object. Speeds in RPM, signed as the
wheel's reference (+ = the wheel rolls forward), times in seconds after the command.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, fields, replace
from typing import Optional

from amr_twin.experiments.chapter5 import payload
from amr_twin.experiments.chapter5.findings import Findings, findings
from amr_twin.experiments.chapter5.readings import readings
from amr_twin.experiments.chapter5.criteria import (
    BANDS,
    DEFINITIONS,
    SOURCES,
    TRANSIENT_WINDOW_S,
    count_checks,
    oscillation_verdict,
)


@dataclass(frozen=True)
class Check:
    """One banded metric of one wheel: the twin's value (None: not measured), the thesis' value,
    the band [low, high] it is judged by, and ``verdict`` "pass" or "fail"."""

    twin: Optional[float]
    thesis: float
    band: list[float]
    verdict: str


@dataclass(frozen=True)
class WheelMetrics:
    """One driven wheel of a run.

    ``reference_rpm``: the wheel_Command's signed speed; ``step_class``: small or large step;
    ``samples``: speeds published; ``published`` / ``true``: the step metrics
    (:meth:`amr_twin.analysis.metrics.StepInfo.as_dict`) of the published samples (None when
    nothing was published) and of the true hinge speed; ``checks`` / ``true_checks``: each
    banded metric of them judged (:func:`amr_twin.experiments.chapter5.criteria.judge`).
    """

    reference_rpm: float
    step_class: str
    samples: int
    published: Optional[dict]
    true: dict
    checks: dict[str, Check]
    true_checks: dict[str, Check]


@dataclass(frozen=True)
class RunMetrics:
    """One chapter 5 run: its number, title, command, payload kg, simulated and wall seconds, the
    wheel_Command and the client's codes and errors, and each driven wheel (``left``, ``right``);
    ``tyre_timestep``: the tyres' guard halved the physics timestep (written only then)."""

    run: int
    title: str
    command: dict
    payload_kg: float
    duration_s: float
    wheel_command: Optional[list]
    codes: list
    errors: list
    wall_s: float
    wheels: dict[str, WheelMetrics]
    tyre_timestep: Optional[dict] = (
        None  # the tyres' guard halved the timestep (amr_twin.model.tyre_stability)
    )


@dataclass(frozen=True)
class OscillationComparison:
    """A loaded run's oscillation against its unloaded twin's, one wheel (§5.1.4: the payload makes
    it oscillate more): on the published samples (judged) and on the true speed, RPM."""

    loaded_run: int
    unloaded_run: int
    wheel: str
    measure: str
    loaded: Optional[float]
    unloaded: Optional[float]
    verdict: str
    true_loaded: Optional[float]
    true_unloaded: Optional[float]
    true_verdict: str


@dataclass(frozen=True)
class CheckCount:
    """Checks made and passed: on the published samples (the banded metrics and the oscillation
    comparisons) and on the true speed (the banded metrics)."""

    checks: int
    passed: int
    true_checks: int
    true_passed: int


@dataclass(frozen=True)
class Chapter5Metrics:
    """Everything ``metrics.json`` holds, in its order.

    The texts (``judged_on``, ``definitions``, ``settling_band``, ``oscillation``) say how the runs
    are judged; ``bands`` the thesis' bands with their sources; ``crr``, ``payload_duty``,
    ``rolling_resistance_study`` and ``threshold_crr`` the §5.1.4 study
    (:mod:`amr_twin.experiments.chapter5.payload`); ``findings`` the thesis' findings judged from
    the rest (:mod:`amr_twin.experiments.chapter5.findings`; None only while it is built);
    ``firmware_comparison`` (another firmware run beside the reference,
    :mod:`amr_twin.experiments.chapter5.firmware_comparison`) and ``spread`` (with parameter draws,
    :mod:`amr_twin.experiments.chapter5.spread`) only when made; ``readings`` the published timings
    under each reading of :mod:`amr_twin.experiments.chapter5.readings` (when the runs carry their
    series); ``attainable`` the committed study of plants inside the sourced ranges, when it applies
    to this plant."""

    firmware: str
    jobs: int
    wall_s: float
    sim_s: float
    study_runs: int
    study_sim_s: float
    judged_on: str
    definitions: dict
    settling_band: str
    oscillation: str
    oscillation_verdict: dict
    bands: list[dict]
    runs: list[RunMetrics]
    comparisons: list[OscillationComparison]
    crr: dict
    payload_duty: list
    rolling_resistance_study: list
    threshold_crr: Optional[float]
    findings: Optional[Findings]
    summary: CheckCount
    firmware_comparison: Optional[dict] = None
    spread: Optional[dict] = None
    readings: Optional[list] = None
    attainable: Optional[dict] = None

    def as_json(self) -> dict:
        """The ``metrics.json`` object (``firmware_comparison`` and ``spread`` only when made)."""
        out = {f.name: getattr(self, f.name) for f in fields(self)}
        out["runs"] = [
            {k: v for k, v in asdict(r).items() if k != "tyre_timestep" or v is not None}
            for r in self.runs
        ]
        out["comparisons"] = [asdict(c) for c in self.comparisons]
        out["summary"] = asdict(self.summary)
        if self.findings is not None:
            out["findings"] = self.findings.as_json()
        for optional in ("firmware_comparison", "spread", "readings", "attainable"):
            if out[optional] is None:
                del out[optional]
        out["summary"] = out.pop("summary")  # the counts close the file
        return out


def _wheel(w: dict) -> WheelMetrics:
    return WheelMetrics(
        w["reference_rpm"],
        w["step_class"],
        w["samples"],
        w["published"],
        w["true"],
        {k: Check(**c) for k, c in w["checks"].items()},
        {k: Check(**c) for k, c in w["true_checks"].items()},
    )


def metrics(results: dict) -> Chapter5Metrics:
    """The typed metrics of :func:`amr_twin.experiments.chapter5.experiment.run`'s ``results``."""
    runs = [
        RunMetrics(
            r["run"],
            r["title"],
            r["command"],
            r["payload_kg"],
            r["duration_s"],
            r["wheel_command"],
            r["codes"],
            r["errors"],
            r["wall_s"],
            {name: _wheel(w) for name, w in r["wheels"].items()},
            r.get("tyre_timestep"),
        )
        for r in results["runs"]
    ]
    comparisons = [OscillationComparison(**c) for c in results["comparisons"]]
    data = Chapter5Metrics(
        firmware=results["firmware"],
        jobs=results["jobs"],
        wall_s=round(results["wall_s"], 3),
        sim_s=results["sim_s"],
        study_runs=results.get("study_runs", 0),
        study_sim_s=results.get("study_sim_s", 0.0),
        judged_on="published samples, linear interpolation from rest at the command",
        definitions=DEFINITIONS,
        settling_band="max(5 % of the step, 4 RPM) around the final value",
        oscillation=f"excess total variation from the first 90 % crossing to "
        f"{TRANSIENT_WINDOW_S:g} s",
        oscillation_verdict=oscillation_verdict(results["comparisons"]),
        bands=[dict(vars(b), source=SOURCES[b.metric]) for b in BANDS],
        runs=runs,
        comparisons=comparisons,
        crr=results["crr"],
        payload_duty=results["payload_duty"],
        rolling_resistance_study=results["rolling_resistance_study"],
        threshold_crr=payload.threshold_crr(
            results["payload_duty"], results["rolling_resistance_study"], results["crr"]["tyres"]
        ),
        findings=None,
        summary=CheckCount(*count_checks(results["runs"], results["comparisons"])),
        firmware_comparison=results.get("firmware_comparison"),
        spread=results.get("spread_summary"),
        readings=readings(results) if all("raw" in r for r in results["runs"]) else None,
        attainable=results.get("attainable"),
    )
    return replace(data, findings=findings(data.as_json()))
