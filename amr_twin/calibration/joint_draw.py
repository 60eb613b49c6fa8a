"""The calibrated parameters drawn jointly (:func:`draw_calibrated`): the calibration's normal,
its mean moved by the held parameters' deviations and conditioned on the members ``--set`` fixes
(docs/how-to/uncertainty.md#amr_twincalibrationuncertainty)."""

from __future__ import annotations

import numpy as np

from amr_twin.model.parameter_spreads import CALIBRATED, EXACT, Spread


def _current(spreads: dict[str, Spread], sample: dict, key: str) -> float:
    return float(sample[key]) if key in sample else float(spreads[key].value)


def draw_calibrated(
    rep,
    spreads: dict[str, Spread],
    values: list[dict],
    block: list[str],
    z: np.ndarray,
    x: np.ndarray,
    col0: int,
) -> None:
    """Fill the calibrated parameters of each sample in ``values``: the fit's mean (``rep``, a
    :class:`~amr_twin.calibration.report.CalibrationReport`) shifted by the held parameters'
    deviations, conditioned on members fixed by the user, plus ``L z`` (``z``: standard normal
    draws, one column per key of ``block``); the drawn values go to ``x``'s columns from
    ``col0``."""
    keys = list(rep.keys)
    held = [(j, k) for j, k in enumerate(rep.held_keys) if k in spreads]
    fixed = [i for i, k in enumerate(keys) if spreads.get(k) and spreads[k].kind == EXACT]
    drawn = [keys.index(k) for k in block]
    shifted = [i for i, k in enumerate(keys) if spreads.get(k) and spreads[k].kind == CALIBRATED]
    if not held and not drawn:
        return
    cov = rep.covariance
    gain = np.zeros((len(drawn), len(fixed)))
    cond = cov[np.ix_(drawn, drawn)]
    if fixed and drawn:
        inv = np.linalg.pinv(cov[np.ix_(fixed, fixed)])
        gain = cov[np.ix_(drawn, fixed)] @ inv
        cond = cond - gain @ cov[np.ix_(fixed, drawn)]
    lam, vec = np.linalg.eigh(0.5 * (cond + cond.T)) if drawn else (np.zeros(0), np.zeros((0, 0)))
    root = vec * np.sqrt(np.clip(lam, 0.0, None))
    for r, sample in enumerate(values):
        dev = np.array([_current(spreads, sample, k) - rep.held_values[j] for j, k in held])
        mean = rep.values + (rep.follow[:, [j for j, _ in held]] @ dev if held else 0.0)
        out = mean.copy()
        if drawn:
            xf = np.array([spreads[keys[i]].value for i in fixed])
            out[drawn] = mean[drawn] + (gain @ (xf - mean[fixed]) if fixed else 0.0) + root @ z[r]
        for i in shifted:
            sample[keys[i]] = float(out[i])
    for c, k in enumerate(block):
        x[:, col0 + c] = [v[k] for v in values]
