"""Step-response metrics of a sampled signal (App. I and fig. 5.3 of the thesis).

:func:`step_info` works on the dense true wheel speed (100 Hz) and on the sparse
speed samples the firmware publishes (one per wheel revolution, about 1 s apart).
Definitions, all times measured from the step instant ``t0_s``:

* the signal and the reference are sign-normalised (a step to -91.67 RPM is
  measured as a step to +91.67 RPM), and the **step size** is
  ``|reference| - initial_value``; the 10/50/90 % levels and the overshoot are
  taken with respect to the **reference** (the line the thesis' plots compare
  against), not to the final value;
* between samples the signal is **interpolated linearly** (the thesis read its
  metrics off rqt_plot curves, which join the published samples by lines); when
  the first sample comes after ``t0_s`` the signal is taken to be at
  ``initial_value`` at ``t0_s`` (the wheel is at rest before the step);
* ``delay_s``: first crossing of 50 % of the step; ``rise_s``: first crossing of
  90 % minus first crossing of 10 %; ``peak_s``, ``peak_value``: first sample
  of the maximum; ``overshoot``: ``max(0, peak_value - reference)`` in the
  signal's units, ``overshoot_pct`` the same in % of the step size;
* ``settling_s``: the time after which the interpolated signal stays within
  ``reference +- settling_band`` until the end of the record (the crossing into
  the band after the last sample outside it); NaN if the last sample is outside;
* ``final_value``: mean of the samples in the last ``final_fraction`` of the
  record (at least the last sample); ``steady_error = final_value - reference``;
* ``oscillation``: **excess total variation** of the signal over the window
  from the first 90 % crossing to ``t0_s + oscillation_window_s`` (the record's
  end by default): ``sum |y[i+1] - y[i]| - |y_end - y_start|``. It is zero for a
  monotone approach and twice the summed swing amplitudes for an oscillating one,
  in the signal's units.

A metric that cannot be measured (the level is never reached) is NaN.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np


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

    def as_dict(self) -> dict:
        """JSON-ready dict; NaN becomes None."""
        return {k: (None if isinstance(v, float) and not math.isfinite(v) else v)
                for k, v in asdict(self).items()}


def _first_crossing_s(t: np.ndarray, y: np.ndarray, level: float) -> float:
    """First time the linear interpolation of (t, y) reaches ``level`` from below; NaN if never."""
    above = np.nonzero(y >= level)[0]
    if len(above) == 0:
        return math.nan
    i = int(above[0])
    if i == 0:
        return float(t[0])
    t0, t1, y0, y1 = t[i - 1], t[i], y[i - 1], y[i]
    return float(t0 + (level - y0) / (y1 - y0) * (t1 - t0))


def _settling_s(t: np.ndarray, y: np.ndarray, reference: float, band: float) -> float:
    """Time from which the interpolated signal stays within reference +- band."""
    error = np.abs(y - reference)
    outside = np.nonzero(error > band)[0]
    if len(outside) == 0:
        return float(t[0])
    i = int(outside[-1])
    if i == len(y) - 1:
        return math.nan
    # the segment i -> i+1 enters the band: interpolate where |error| meets the band
    bound = reference + band if y[i] > reference else reference - band
    return float(t[i] + (bound - y[i]) / (y[i + 1] - y[i]) * (t[i + 1] - t[i]))


def _excess_variation(t: np.ndarray, y: np.ndarray, t_start_s: float, t_end_s: float) -> float:
    """Total variation of the interpolated signal on [t_start_s, t_end_s] minus its net change."""
    if not (math.isfinite(t_start_s) and t_end_s > t_start_s):
        return math.nan
    inner = (t > t_start_s) & (t < t_end_s)
    tw = np.concatenate([[t_start_s], t[inner], [t_end_s]])
    yw = np.interp(tw, t, y)
    return float(np.sum(np.abs(np.diff(yw))) - abs(yw[-1] - yw[0]))


def step_info(t_s, y, reference: float, t0_s: float = 0.0, settling_band: float | None = None,
              initial_value: float | None = 0.0, final_fraction: float = 0.2,
              oscillation_window_s: float | None = None) -> StepInfo:
    """Step-response metrics of a sampled signal (see the module docstring).

    Parameters
    ----------
    t_s : (n,) sample times, s, increasing.
    y : (n,) signal, any unit (RPM for wheel speeds); signed or magnitude.
    reference : the step's target value, same unit; its sign normalises ``y``.
    t0_s : time of the step, s; samples before it are ignored.
    settling_band : half-width of the settling band around the reference, in the
        signal's units; default 5 % of the step size.
    initial_value : value of the signal at ``t0_s`` when no sample lies there
        (None: use the first sample as is).
    final_fraction : fraction of the record (after ``t0_s``) averaged for the final value.
    oscillation_window_s : end of the oscillation window, s after ``t0_s``
        (None: the end of the record).

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
    step = ref - y_start
    band = 0.05 * abs(step) if settling_band is None else float(settling_band)
    level = lambda fraction: y_start + fraction * step  # noqa: E731
    t10, t50, t90 = (_first_crossing_s(t, y, level(f)) for f in (0.1, 0.5, 0.9))
    i_peak = int(np.argmax(y))
    peak_value = float(y[i_peak])
    overshoot = max(0.0, peak_value - ref)
    in_tail = t >= t[-1] - final_fraction * (t[-1] - t[0])  # always holds the last sample
    final_value = float(np.mean(y[in_tail]))
    t_end = t[-1] if oscillation_window_s is None else min(t[-1], oscillation_window_s)
    return StepInfo(
        reference=ref, final_value=final_value, delay_s=t50, rise_s=t90 - t10,
        peak_s=float(t[i_peak]), peak_value=peak_value, overshoot=overshoot,
        overshoot_pct=100.0 * overshoot / abs(step) if step else math.nan,
        settling_s=_settling_s(t, y, ref, band), settling_band=band,
        steady_error=final_value - ref, oscillation=_excess_variation(t, y, t90, t_end))
