"""The thesis' chapter 5 findings, each judged reproduced or not from the ``metrics.json`` object.

:func:`findings` reads the object :meth:`.metrics.Chapter5Metrics.as_json` writes (runs,
comparisons, payload_duty) and returns a :class:`Findings`: one :class:`Finding` per statement of
§5.1.3/§5.1.4 with its verdict and a one-line why, the bound listing 4.12 puts on each published
timing (:class:`TimingBound`), and the published checks split into attainable and unattainable
(:class:`CheckSplit`). Speeds in RPM, times in seconds after the command; the bound in
:mod:`.timing_bound`.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

from amr_twin.controllers.firmware_params import FaithfulParams
from amr_twin.experiments.chapter5.criteria import BANDS
from amr_twin.experiments.chapter5.timing_bound import TIMINGS, TimingBound, timing_bounds

REPRODUCED, NOT_REPRODUCED, NOT_JUDGED = "reproduced", "not reproduced", "not judged"
DEAD_ZONE_RPM = FaithfulParams.threshold_control_rpm  # listing 4.11's THRESHOLD_CONTROL
RIGHT_MARGIN_RPM = 1.0  # "lower" left overshoot: at least this far below the right's
MIXED_RUNS_SHARE = 4 / 6  # runs 3-8: the right wheel overshoots more in at least 4 of 6
OSCILLATION_SHARE = 3 / 4  # 20 kg oscillates more in at least 3 of the 4 comparisons
VALIDATION_DOC = "docs/explanation/validation.md"
"""Where the chapter 5 findings and the bound are explained, relative to the repository's root."""
VALIDATION_SECTION = "What the chapter 5 report states first"
ATTAINABLE_SECTION = "Can a plant inside the sourced ranges meet the findings?"
ATTAINABLE_COMMAND = "amr-twin experiment chapter5-attainable"
"""Whether any plant inside the parameters' sourced ranges meets the findings: the command, its
section."""


@dataclass(frozen=True)
class Finding:
    """One finding of the thesis: ``key``, the ``claim`` and its ``source``, ``verdict``
    (reproduced, not reproduced or not judged) and ``why``, one line with the figures."""

    key: str
    claim: str
    source: str
    verdict: str
    why: str


@dataclass(frozen=True)
class CheckSplit:
    """The published checks (banded metrics and oscillation comparisons) split by the bound, each
    with how many pass; ``true_timing``: the true speed's timing checks, which have no such
    bound."""

    attainable: int
    attainable_passed: int
    unattainable: int
    unattainable_passed: int
    true_timing: int
    true_timing_passed: int


@dataclass(frozen=True)
class Findings:
    """The findings (a-e of the report's top), the per-wheel timing bounds and the split counts."""

    findings: list[Finding]
    bounds: list[TimingBound]
    checks: CheckSplit
    explained_in: str = VALIDATION_DOC

    def as_json(self) -> dict:
        """The ``findings`` entry of ``metrics.json``."""
        return asdict(self)


def _verdict(ok: bool) -> str:
    return REPRODUCED if ok else NOT_REPRODUCED


def _band(metric: str, wheel: str) -> tuple[float, float]:
    band = next(b for b in BANDS if b.metric == metric and b.wheel in (wheel, "any"))
    return band.low, band.high


def _num(value: float | None, fmt: str = ".2f") -> str:
    return "—" if value is None or not math.isfinite(value) else format(value, fmt)


def _value(runs: dict, run: int, wheel: str, key: str, source: str = "published") -> float | None:
    w = runs.get(run, {}).get("wheels", {}).get(wheel)
    value = None if w is None else (w.get(source) or {}).get(key)
    return None if value is None or not math.isfinite(value) else value


def overshoot_finding(runs: dict) -> Finding:
    """§5.1.3: the right wheel overshoots about 4 RPM, the left less or not at all (runs 1-8)."""
    claim, source = "right wheel overshoots ≈4 RPM, left less (≈2)", "§5.1.3"
    r, left = _value(runs, 2, "right", "overshoot"), _value(runs, 1, "left", "overshoot")
    rt, lt = (
        _value(runs, 2, "right", "overshoot", "true"),
        _value(runs, 1, "left", "overshoot", "true"),
    )
    if r is None or left is None or rt is None or lt is None:
        return Finding(
            "overshoot_right", claim, source, NOT_JUDGED, "runs 1 and 2 not both measured"
        )
    (rlo, rhi), (llo, lhi) = _band("overshoot", "right"), _band("overshoot", "left")
    mixed = [n for n in range(3, 9) if n in runs and {"left", "right"} <= set(runs[n]["wheels"])]
    more = [
        n
        for n in mixed
        if (_value(runs, n, "right", "overshoot") or 0.0)
        > (_value(runs, n, "left", "overshoot") or 0.0)
    ]
    needed = math.ceil(MIXED_RUNS_SHARE * len(mixed) - 1e-9)
    ok = (
        rlo <= r <= rhi
        and llo <= left <= lhi
        and r >= left + RIGHT_MARGIN_RPM
        and rt >= lt + RIGHT_MARGIN_RPM
        and len(more) >= needed
    )
    why = (
        f"runs 2/1 published right {r:.2f} vs left {left:.2f} RPM (needs right {rlo:g}-{rhi:g}, "
        f"left {llo:g}-{lhi:g}, right >= left + {RIGHT_MARGIN_RPM:g}); true {rt:.2f} vs {lt:.2f}; "
        f"runs 3-8: right above left in {len(more)} of {len(mixed)} (needs {needed})"
    )
    return Finding("overshoot_right", claim, source, _verdict(ok), why)


def tracking_finding(runs: dict) -> Finding:
    """§5.1.3: unloaded runs track "almost perfectly", i.e. end within the PI's dead zone."""
    claim = f"unloaded runs track the reference (±{DEAD_ZONE_RPM:g} RPM dead zone)"
    source = "§5.1.3, listing 4.11"
    errors = [
        (r["run"], name, _value(runs, r["run"], name, "steady_error"))
        for r in runs.values()
        if r["payload_kg"] == 0
        for name in r["wheels"]
    ]
    if not errors:
        return Finding("tracking", claim, source, NOT_JUDGED, "no unloaded run")
    inside = [e for e in errors if e[2] is not None and abs(e[2]) <= DEAD_ZONE_RPM]
    run, wheel, worst = max(errors, key=lambda e: math.inf if e[2] is None else abs(e[2]))
    why = (
        f"{len(inside)} of {len(errors)} unloaded wheels end within ±{DEAD_ZONE_RPM:g} RPM "
        f"(published); "
        f"worst run {run} {wheel} {_num(worst, '+.2f')} RPM"
    )
    return Finding("tracking", claim, source, _verdict(len(inside) == len(errors)), why)


def duty_finding(payload_duty: list[dict]) -> Finding:
    """§5.1.4: with 20 kg the PI raises the duty on both wheels of runs 7 and 8."""
    claim, source = "20 kg: the PI raises the duty (runs 7, 8)", "§5.1.4"
    if not payload_duty:
        return Finding(
            "duty_raised", claim, source, NOT_JUDGED, "no 20 kg run with its unloaded twin"
        )
    raised = sum(bool(c["raised"]) for c in payload_duty)
    counts = ", ".join(
        f"{c['loaded_run']} {c['wheel']} {c['loaded']['counts']:.1f}/{c['unloaded']['counts']:.1f}"
        for c in payload_duty
    )
    why = f"raised on {raised} of {len(payload_duty)} wheels (counts 20 kg/unloaded: {counts})"
    return Finding("duty_raised", claim, source, _verdict(raised == len(payload_duty)), why)


def oscillation_finding(comparisons: list[dict]) -> Finding:
    """§5.1.4: more oscillation during the transient with 20 kg, on the samples and on the true
    speed."""
    claim, source = "20 kg: more oscillation in the transient", "§5.1.4"
    n = len(comparisons)
    if not n:
        return Finding(
            "oscillation", claim, source, NOT_JUDGED, "no 20 kg run with its unloaded twin"
        )
    needed = math.ceil(OSCILLATION_SHARE * n - 1e-9)
    pub = sum(c["verdict"] == "pass" for c in comparisons)
    true = sum(c.get("true_verdict") == "pass" for c in comparisons)
    why = (
        f"20 kg oscillates more in {pub} of {n} comparisons on the published samples, {true} of "
        f"{n} "
        f"on the true speed (needs {needed} on each; excess total variation)"
    )
    return Finding("oscillation", claim, source, _verdict(pub >= needed and true >= needed), why)


def timing_finding(runs: dict, bounds: list[TimingBound]) -> Finding:
    """§5.1.3's delay, rise, peak and settling times: reproduced when every published timing check
    the bound leaves attainable passes; the unattainable ones and the true speed's are counted in
    ``why``."""
    claim, source = "delay, rise, peak, settling times", "§5.1.3, fig. 5.3"
    if not bounds:
        return Finding("timings", claim, source, NOT_JUDGED, "no driven wheel")
    verdict = {
        (r["run"], name, m): c["verdict"]
        for r in runs.values()
        for name, w in r["wheels"].items()
        for m, c in w["checks"].items()
    }
    reach = [b for b in bounds if b.attainable]
    passed = sum(verdict[(b.run, b.wheel, b.metric)] == "pass" for b in reach)
    true = [
        c
        for r in runs.values()
        for w in r["wheels"].values()
        for m, c in w["true_checks"].items()
        if m in TIMINGS
    ]
    true_passed = sum(c["verdict"] == "pass" for c in true)
    why = (
        f"{len(bounds) - len(reach)} of {len(bounds)} published timing checks out of reach under "
        f"listing 4.12; attainable {passed} of {len(reach)} pass; true speed {true_passed} of "
        f"{len(true)}"
    )
    return Finding("timings", claim, source, _verdict(passed == len(reach)), why)


def findings(data: dict) -> Findings:
    """The findings of the ``metrics.json`` object ``data`` (without its ``findings`` key)."""
    runs = {r["run"]: r for r in data["runs"]}
    bounds = timing_bounds(runs, per_revolution=data.get("firmware") != "improved")
    out = [
        overshoot_finding(runs),
        tracking_finding(runs),
        duty_finding(data.get("payload_duty") or []),
        oscillation_finding(data.get("comparisons") or []),
        timing_finding(runs, bounds),
    ]
    unreachable = {(b.run, b.wheel, b.metric) for b in bounds if not b.attainable}
    checks = [
        ((r["run"], name, m), c["verdict"] == "pass")
        for r in runs.values()
        for name, w in r["wheels"].items()
        for m, c in w["checks"].items()
    ]
    checks += [(None, c["verdict"] == "pass") for c in data.get("comparisons") or []]
    off = [ok for key, ok in checks if key in unreachable]
    on = [ok for key, ok in checks if key not in unreachable]
    true = [
        c["verdict"] == "pass"
        for r in runs.values()
        for w in r["wheels"].values()
        for m, c in w["true_checks"].items()
        if m in TIMINGS
    ]
    return Findings(
        out, bounds, CheckSplit(len(on), sum(on), len(off), sum(off), len(true), sum(true))
    )


def lines(found: dict) -> list[str]:
    """The findings block, one line each: the findings, the attainable checks, the unattainable ones
    with their bound (``found``: :meth:`Findings.as_json`); the caller adds the pointer to
    :data:`VALIDATION_DOC`."""
    out = [f"[{f['verdict']}] {f['claim']} ({f['source']}): {f['why']}" for f in found["findings"]]
    c = found["checks"]
    out.append(
        f"attainable checks passed {c['attainable_passed']}/{c['attainable']} on the published "
        "samples (overshoot, steady error, oscillation comparisons and the timings listing 4.12 "
        f"leaves in reach); true-speed timings {c['true_timing_passed']}/{c['true_timing']}"
    )
    groups: dict[float, list[dict]] = {}
    for b in found["bounds"]:
        if not b["attainable"]:
            groups.setdefault(round(abs(b["reference_rpm"]), 2), []).append(b)
    parts = []
    for ref, bs in sorted(groups.items()):
        runs = ", ".join(str(n) for n in sorted({b["run"] for b in bs}))
        seen = {b["metric"]: b for b in bs}
        limits = ", ".join(
            f"{m.removesuffix('_s')} >= {b['bound_s']:.2f} > {b['band_high_s']:g}"
            for m, b in seen.items()
        )
        parts.append(f"T = {60.0 / ref:.2f} s at {ref:.2f} RPM (runs {runs}: {limits} s)")
    out.append(
        "unattainable under listing 4.12 (one speed per wheel revolution, the first >= T = "
        f"60/|rpm| s after the command): {c['unattainable']} checks, {c['unattainable_passed']} "
        f"pass" + (f"; {'; '.join(parts)}" if parts else "")
    )
    return out
