"""Chapter 5's criteria: the thesis' bands for each metric (§5.1.3) and the 20 kg oscillation check
(§5.1.4).

The metrics (:mod:`amr_twin.analysis.metrics`: Ogata's definitions, which the thesis' fig. 5.3
lists) are judged on the **published** samples (``wheel0_Vel``/``wheel1_Vel``, what the
thesis plotted), joined by straight lines and starting from rest at the command; the true
wheel speed is judged against the same bands too, and counted apart (the thesis could not see
it, but its timings describe it better: ``docs/explanation/validation.md``). Settling band:
``max(5 % of the step, 4 RPM)`` around the final value; 4 RPM is the firmware's
THRESHOLD_CONTROL, inside which the PI does not act. The overshoot is the peak above the
final value (0 without a peak); the steady error, the final value's offset from the
reference, is judged on its own against that same dead zone: §5.1.3's "almost perfect track
of the reference" cannot be read tighter than the 4 RPM within which the faithful PI stops
correcting, nor looser, since outside it the PI should have corrected.
Oscillation (the 20 kg runs' "more oscillation", §5.1.4): the named measure
:data:`OSCILLATION_MEASURE`, the excess total variation of the speed from its
first 90 % crossing to 5 s after the command (:func:`amr_twin.analysis.metrics.step_info`),
compared per wheel between each 20 kg run and the same command unloaded; the
verdict is judged on the published samples, the true speed's is reported too.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

WHEELS = ("left", "right")
STEP_SPLIT_RPM = 75.0  # the thesis' split: "steps valued at maximum 75 RPM" and higher
THRESHOLD_CONTROL_RPM = 4.0
TRANSIENT_WINDOW_S = 5.0  # oscillation is measured from the 90 % crossing to 5 s after the command


@dataclass(frozen=True)
class Band:
    """An accepted range for one metric of the published samples (§5.1.3)."""

    metric: str
    step_class: str  # "small" (<= 75 RPM), "large" (> 75 RPM) or "any"
    wheel: str  # "left", "right" or "any"
    low: float
    high: float
    thesis: float  # the value the thesis reports


BANDS = (
    Band("delay_s", "small", "any", 0.1, 0.3, 0.2),
    Band("rise_s", "small", "any", 0.3, 0.7, 0.5),
    Band("peak_s", "small", "any", 0.4, 0.8, 0.6),
    Band("delay_s", "large", "any", 0.3, 0.7, 0.5),
    Band("rise_s", "large", "any", 0.7, 1.3, 1.0),
    Band("peak_s", "large", "any", 0.8, 1.4, 1.1),
    Band("settling_s", "any", "any", 0.0, 1.6, 1.3),
    Band("overshoot", "any", "right", 2.0, 6.0, 4.0),
    Band("overshoot", "any", "left", 0.0, 3.0, 2.0),
    Band("steady_error", "any", "any", -THRESHOLD_CONTROL_RPM, THRESHOLD_CONTROL_RPM, 0.0),
)
SOURCES = {
    "delay_s": "§5.1.3, fig. 5.3",
    "rise_s": "§5.1.3, fig. 5.3",
    "peak_s": "§5.1.3, fig. 5.3",
    "settling_s": "§5.1.3, fig. 5.3",
    "overshoot": "§5.1.3, fig. 5.3",
    "steady_error": '§5.1.3 ("almost perfect track"), listing 4.11\'s THRESHOLD_CONTROL',
}
"""Where each band's thesis value is stated."""
DEFINITIONS = (
    "Ogata, Modern Control Engineering, 5th ed., §5-3 (the specifications of the thesis' fig. "
    "5.3): "
    "delay = first 50 % of the final value, rise = 10 → 90 % of the final value, peak time = "
    "first peak "
    "when the response crosses its final value and comes back (each by more than 0.1 % of the "
    "step), "
    "overshoot = maximum peak − final value (0 without a peak), settling = last entry into the "
    "band around the final value; steady error "
    "= final value − reference (§5-8), the final value the mean of the last 20 % of the record"
)
OSCILLATION_PAIRS = ((7, 3), (8, 5))  # (loaded, unloaded): "more oscillation" with 20 kg (§5.1.4)
OSCILLATION_MEASURE = "excess total variation"
OSCILLATION_DEFINITION = (
    f"excess total variation of the wheel speed from its first 90 % crossing to "
    f"{TRANSIENT_WINDOW_S:g} s after the command: sum |y[i+1] - y[i]| - |y_end - y_start| "
    "on the linearly interpolated signal, RPM (0 for a monotone approach, twice the summed "
    "swing amplitudes otherwise)"
)


def step_class(step_rpm: float) -> str:
    """ "small" for steps of at most 75 RPM, "large" above."""
    return "small" if abs(step_rpm) <= STEP_SPLIT_RPM else "large"


def settling_band_rpm(step_rpm: float) -> float:
    """Half-width of the settling band: 5 % of the step, at least the PI's 4 RPM dead zone."""
    return max(0.05 * abs(step_rpm), THRESHOLD_CONTROL_RPM)


def judge(wheel: str, step_rpm: float, metrics: dict) -> dict:
    """Verdict of each banded metric: ``{metric: {twin, thesis, band, verdict}}``.

    A metric that could not be measured (None/NaN) fails.
    """
    out = {}
    cls = step_class(step_rpm)
    for band in BANDS:
        if band.step_class not in ("any", cls) or band.wheel not in ("any", wheel):
            continue
        value = metrics.get(band.metric)
        ok = value is not None and math.isfinite(value) and band.low <= value <= band.high
        out[band.metric] = {
            "twin": value,
            "thesis": band.thesis,
            "band": [band.low, band.high],
            "verdict": "pass" if ok else "fail",
        }
    return out


def _more(loaded: float | None, unloaded: float | None) -> str:
    ok = loaded is not None and unloaded is not None and loaded > unloaded
    return "pass" if ok else "fail"


def compare_oscillation(results: list[dict]) -> list[dict]:
    """Loaded against unloaded oscillation, per driven wheel of each pair of
    :data:`OSCILLATION_PAIRS`.

    Returns
    -------
    list of dict : ``loaded_run, unloaded_run, wheel, measure``; ``loaded``,
    ``unloaded`` and ``verdict`` on the published samples (the judged values);
    ``true_loaded``, ``true_unloaded`` and ``true_verdict`` on the true speed.
    A value that could not be measured (None) fails.
    """
    by_number = {r["run"]: r for r in results}
    out = []
    for loaded, unloaded in OSCILLATION_PAIRS:
        if loaded not in by_number or unloaded not in by_number:
            continue
        for wheel in WHEELS:
            a = by_number[loaded]["wheels"].get(wheel)
            b = by_number[unloaded]["wheels"].get(wheel)
            if a is None or b is None:
                continue
            va, vb = ((w.get("published") or {}).get("oscillation") for w in (a, b))
            ta, tb = ((w.get("true") or {}).get("oscillation") for w in (a, b))
            out.append(
                {
                    "loaded_run": loaded,
                    "unloaded_run": unloaded,
                    "wheel": wheel,
                    "measure": OSCILLATION_MEASURE,
                    "loaded": va,
                    "unloaded": vb,
                    "verdict": _more(va, vb),
                    "true_loaded": ta,
                    "true_unloaded": tb,
                    "true_verdict": _more(ta, tb),
                }
            )
    return out


def oscillation_verdict(comparisons: list[dict]) -> dict:
    """Overall "the 20 kg runs oscillate more" verdict: it holds only if every comparison passes.

    Returns
    -------
    dict : ``{"measure", "definition", "published_passed", "true_passed", "comparisons",
    "verdict"}`` with ``verdict`` "pass" or "fail" (judged on the published samples; "fail" when
    there is no pair)."""
    n = len(comparisons)
    passed = sum(c["verdict"] == "pass" for c in comparisons)
    return {
        "measure": OSCILLATION_MEASURE,
        "definition": OSCILLATION_DEFINITION,
        "comparisons": n,
        "published_passed": passed,
        "true_passed": sum(c.get("true_verdict") == "pass" for c in comparisons),
        "verdict": "pass" if n and passed == n else "fail",
    }


def count_checks(runs: list[dict], comparisons: list[dict]) -> tuple[int, int, int, int]:
    """The scorecard's counts of analysed runs (:func:`.runs.analyse`'s dicts) and their
    oscillation comparisons (:func:`compare_oscillation`).

    Returns
    -------
    (checks, passed, true_checks, true_passed) : the banded metrics of the published samples
    and the comparisons' published verdicts; the banded metrics of the true speed.
    """
    checks = [c for r in runs for w in r["wheels"].values() for c in w["checks"].values()]
    true_checks = [c for r in runs for w in r["wheels"].values() for c in w["true_checks"].values()]
    passed = sum(c["verdict"] == "pass" for c in checks) + sum(
        c["verdict"] == "pass" for c in comparisons
    )
    return (
        len(checks) + len(comparisons),
        passed,
        len(true_checks),
        sum(c["verdict"] == "pass" for c in true_checks),
    )
