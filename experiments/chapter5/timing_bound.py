"""Listing 4.12's lower bound on each published timing of chapter 5 (:func:`timing_bounds`).

Listing 4.12 publishes one speed per wheel revolution, the mean over that revolution, counted from
after the command and from after the previous sample. A sample ``y`` therefore comes at least
``60 / y`` s after the one before, and the straight line the metrics join the samples with (from
rest at the command) climbs at most ``y^2 / 60`` RPM/s. With samples no faster than the reference
``r`` before a level is crossed, with ``T = 60 / |r|`` (one revolution at the reference): delay
(50 %) >= 0.5 T, rise (10-90 %) >= 0.8 T, settling >= (1 - band / |r|) T, and the peak, itself a
sample, >= T. A band whose upper end lies below its bound cannot be met by any plant; the improved
firmware, which publishes at 10 Hz, has no such bound.
"""

from __future__ import annotations

from dataclasses import dataclass

from amr_twin.experiments.chapter5.criteria import settling_band_rpm

TIMINGS = {
    "delay_s": 0.5,
    "rise_s": 0.8,
    "peak_s": 1.0,
    "settling_s": None,
}  # bound / T (settling: band)


@dataclass(frozen=True)
class TimingBound:
    """Listing 4.12's lower bound on one published timing of one wheel, s (``bound_s``), against the
    band's upper end (``band_high_s``) and the twin's value (``twin_s``, None: not measured)."""

    run: int
    wheel: str
    reference_rpm: float
    metric: str
    bound_s: float
    band_high_s: float
    twin_s: float | None
    attainable: bool


def timing_bounds(runs: dict, per_revolution: bool = True) -> list[TimingBound]:
    """Listing 4.12's bound on each published timing check of each driven wheel (module docstring);
    with ``per_revolution`` False (a firmware publishing per edge) every bound is 0."""
    out = []
    for r in runs.values():
        for name, w in r["wheels"].items():
            ref = abs(w["reference_rpm"])
            rev_s = 60.0 / ref
            for metric, share in TIMINGS.items():
                check = w["checks"].get(metric)
                if check is None:
                    continue
                if share is None:
                    share = max(0.0, 1.0 - settling_band_rpm(ref) / ref)
                bound = share * rev_s if per_revolution else 0.0
                high = check["band"][1]
                out.append(
                    TimingBound(
                        r["run"],
                        name,
                        w["reference_rpm"],
                        metric,
                        bound,
                        high,
                        check["twin"],
                        bound <= high,
                    )
                )
    return out
