"""Step-response metrics of a sampled signal: the time-domain specifications of fig. 5.3 and App. I.

Reasons and measurements: docs/explanation/validation.md#amr_twinanalysismetrics."""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np


SIGNED_METRICS = ("reference", "final_value", "peak_value", "steady_error")
"""Metrics measured along the reference that carry its sign in :meth:`StepInfo.as_dict`
(the overshoot, the band and the oscillation are magnitudes)."""


@dataclass(frozen=True)
class StepInfo:
    """Named step-response metrics; times in s, values in the signal's units (RPM here)."""

    reference: float
    final_value: float
    delay_s: float
    rise_s: float
    peak_s: float
    peak_value: float
    overshoot: float
    overshoot_pct: float
    settling_s: float
    settling_band: float
    steady_error: float
    oscillation: float

    def as_dict(self, sign: float = 1.0) -> dict:
        """JSON-ready dict; NaN becomes None. With ``sign`` -1 (a step to a negative
        reference) the values of :data:`SIGNED_METRICS` carry the reference's sign; the
        others are magnitudes or times."""
        return {
            k: (
                None
                if isinstance(v, float) and not math.isfinite(v)
                else (sign * v if k in SIGNED_METRICS else v)
            )
            for k, v in asdict(self).items()
        }


def first_crossing_s(t: np.ndarray, y: np.ndarray, level: float) -> float:
    """First time the linear interpolation of (t, y) reaches ``level`` from below; NaN if never."""
    above = np.nonzero(y >= level)[0]
    if len(above) == 0:
        return math.nan
    i = int(above[0])
    if i == 0:
        return float(t[0])
    t0, t1, y0, y1 = t[i - 1], t[i], y[i - 1], y[i]
    return float(t0 + (level - y0) / (y1 - y0) * (t1 - t0))


def _settling_s(t: np.ndarray, y: np.ndarray, centre: float, band: float) -> float:
    """Time from which the interpolated signal stays within centre +- band."""
    error = np.abs(y - centre)
    outside = np.nonzero(error > band)[0]
    if len(outside) == 0:
        return float(t[0])
    i = int(outside[-1])
    if i == len(y) - 1:
        return math.nan
    # the segment i -> i+1 enters the band: interpolate where |error| meets the band
    bound = centre + band if y[i] > centre else centre - band
    return float(t[i] + (bound - y[i]) / (y[i + 1] - y[i]) * (t[i + 1] - t[i]))


def _peak(y: np.ndarray, final_value: float, tolerance: float) -> int | None:
    """Index of the response's maximum peak (first sample of its maximum) if it crosses its final
    value and comes back, each by more than ``tolerance``; None for a monotone approach."""
    i = int(np.argmax(y))
    if y[i] - final_value <= tolerance or i == len(y) - 1:
        return None
    return i if float(np.min(y[i + 1 :])) < y[i] - tolerance else None


def _first_peak(y: np.ndarray, final_value: float, tolerance: float, last: int) -> int:
    """Index of the first peak, at or before the maximum peak ``last``: the first sample above
    ``final_value + tolerance`` from which ``y`` falls by more than ``tolerance`` before it
    exceeds that sample (Ogata's t_p; the maximum peak itself qualifies)."""
    for i in np.nonzero(y[:last] > final_value + tolerance)[0]:
        after = y[i + 1 :]
        back = np.nonzero(after < y[i] - tolerance)[0]
        over = np.nonzero(after > y[i])[0]
        if len(back) and (not len(over) or back[0] < over[0]):
            return int(i)
    return last


def _excess_variation(t: np.ndarray, y: np.ndarray, t_start_s: float, t_end_s: float) -> float:
    """Total variation of the interpolated signal on [t_start_s, t_end_s] minus its net change."""
    if not (math.isfinite(t_start_s) and t_end_s > t_start_s):
        return math.nan
    inner = (t > t_start_s) & (t < t_end_s)
    tw = np.concatenate([[t_start_s], t[inner], [t_end_s]])
    yw = np.interp(tw, t, y)
    return float(np.sum(np.abs(np.diff(yw))) - abs(yw[-1] - yw[0]))


def step_info(
    t_s,
    y,
    reference: float,
    t0_s: float = 0.0,
    settling_band: float | None = None,
    initial_value: float | None = 0.0,
    final_fraction: float = 0.2,
    oscillation_window_s: float | None = None,
    peak_tolerance: float | None = None,
) -> StepInfo:
    """Step-response metrics of a sampled signal (see the module docstring).

    Parameters
    ----------
    t_s : (n,) sample times, s, increasing.
    y : (n,) signal, any unit (RPM for wheel speeds); signed or magnitude.
    reference : the step's target value, same unit; its sign normalises ``y``.
    t0_s : time of the step, s; samples before it are ignored.
    settling_band : half-width of the settling band around the final value, in the
        signal's units; default 5 % of the step.
    initial_value : value of the signal at ``t0_s`` when no sample lies there
        (None: use the first sample as is).
    final_fraction : fraction of the record (after ``t0_s``) averaged for the final value.
    oscillation_window_s : end of the oscillation window, s after ``t0_s``
        (None: the end of the record).
    peak_tolerance : how far above its final value, and back below its maximum, the signal
        must go to have a peak, in the signal's units; default 0.1 % of the step.

    Returns
    -------
    StepInfo
    """
    t = np.asarray(t_s, float).ravel()
    y = np.asarray(y, float).ravel()
    if t.shape != y.shape:
        raise ValueError(f"t_s and y must have the same length, got {t.shape} and {y.shape}")
    if not math.isfinite(reference) or reference == 0.0:
        raise ValueError(f"reference: {reference} must be a finite non-zero number")
    sign = 1.0 if reference > 0 else -1.0
    ref = abs(reference)
    keep = t >= t0_s
    t, y = t[keep] - t0_s, y[keep] * sign
    if initial_value is not None and (len(t) == 0 or t[0] > 0.0):
        t, y = np.concatenate([[0.0], t]), np.concatenate([[abs(initial_value)], y])
    if len(t) < 2:
        raise ValueError("step_info needs at least two samples at or after t0_s")
    y_start = y[0]
    in_tail = t >= t[-1] - final_fraction * (t[-1] - t[0])  # always holds the last sample
    final_value = float(np.mean(y[in_tail]))
    step = final_value - y_start
    band = 0.05 * abs(step) if settling_band is None else float(settling_band)
    if step > 0.0:
        t10, t50, t90 = (first_crossing_s(t, y, y_start + f * step) for f in (0.1, 0.5, 0.9))
    else:  # the signal ends where it started, or on the other side: no rise to time
        t10 = t50 = t90 = math.nan
    tolerance = 1e-3 * abs(step) if peak_tolerance is None else float(peak_tolerance)
    i_peak = _peak(y, final_value, tolerance)
    i_first = None if i_peak is None else _first_peak(y, final_value, tolerance, i_peak)
    overshoot = 0.0 if i_peak is None else float(y[i_peak]) - final_value
    t_end = t[-1] if oscillation_window_s is None else min(t[-1], oscillation_window_s)
    return StepInfo(
        reference=ref,
        final_value=final_value,
        delay_s=t50,
        rise_s=t90 - t10,
        peak_s=math.nan if i_first is None else float(t[i_first]),
        peak_value=math.nan if i_peak is None else float(y[i_peak]),
        overshoot=overshoot,
        overshoot_pct=100.0 * overshoot / abs(step) if step else math.nan,
        settling_s=_settling_s(t, y, final_value, band),
        settling_band=band,
        steady_error=final_value - ref,
        oscillation=_excess_variation(t, y, t90, t_end),
    )
