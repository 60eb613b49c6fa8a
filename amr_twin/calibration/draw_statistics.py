"""Results summarised over parameter draws: the median and an interval (:func:`interval`), the
Spearman rank correlation of each drawn parameter with a result (:func:`rank_correlations`) and
the correlation chance alone reaches (:func:`noise_level`)."""

from __future__ import annotations

import math
from typing import Sequence

import numpy as np

LEVEL = 0.90  # the reported interval: 5 % to 95 %


def interval(values: Sequence[float | None], level: float = LEVEL, discrete: bool = False) -> dict:
    """``{"median", "low", "high", "n"}``: the median and the ``level`` interval's quantiles of
    ``values`` (None and NaN left out; None for each when none is left).

    ``discrete``: quantiles that are values of the sample (numpy's ``inverted_cdf``), for
    answers on a grid or censored at ``±inf``, which are kept; otherwise linear
    interpolation between the finite values.
    """
    v = np.array([x for x in values if x is not None and not math.isnan(x)], dtype=float)
    if not discrete:
        v = v[np.isfinite(v)]
    if not len(v):
        return {"median": None, "low": None, "high": None, "n": 0}
    lo, med, hi = np.quantile(
        v, [(1 - level) / 2, 0.5, (1 + level) / 2], method="inverted_cdf" if discrete else "linear"
    )
    return {"median": float(med), "low": float(lo), "high": float(hi), "n": int(len(v))}


def rank_correlations(x: np.ndarray, y: Sequence[float | None]) -> np.ndarray:
    """(d,) Spearman rank correlation of each column of ``x`` (n, d) with ``y`` (n,), over the
    samples where ``y`` is a number (``±inf``, a censored answer, ranks last or first); NaN
    for a constant column or fewer than 3 samples."""
    from scipy.stats import rankdata

    y = np.array([np.nan if v is None else float(v) for v in y])
    ok = ~np.isnan(y)
    out = np.full(x.shape[1], np.nan)
    if ok.sum() < 3 or len(set(y[ok].tolist())) < 2:
        return out
    ry = rankdata(y[ok])
    ry = (ry - ry.mean()) / np.linalg.norm(ry - ry.mean())
    for j in range(x.shape[1]):
        rx = rankdata(x[ok, j])
        norm_x = np.linalg.norm(rx - rx.mean())
        if norm_x > 0:
            out[j] = float((rx - rx.mean()) @ ry / norm_x)
    return out


def noise_level(n: int, parameters: int = 1) -> float:
    """|rho| that the largest of ``parameters`` unrelated ones exceeds in ``n`` samples about one
    time in 20 (two-sided, Bonferroni: ``Phi^-1(1 - 0.025 / parameters) / sqrt(n - 1)``)."""
    from scipy.stats import norm

    return float(norm.ppf(1 - 0.025 / max(parameters, 1)) / math.sqrt(max(n - 1, 1)))
