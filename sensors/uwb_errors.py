"""Error model of a DW1000 two-way ranging exchange: white noise, NLOS bias, a wall's bias and
loss, dropouts (the ``uwb:`` section of ``models/amr/amr.yaml``; Decawave APS006 part 1, APS013).

:func:`corrupt_ranges` corrupts a batch of exchanges, :func:`corrupt_range` one, with the same
draws in the same order (the sensor: :mod:`amr_twin.sensors.uwb`).
"""

from __future__ import annotations

import numpy as np

from amr_twin.model.config_sensors import UwbCfg


def corrupt_ranges(
    true_range_m: np.ndarray,
    cfg: UwbCfg,
    rng: np.random.Generator,
    blocked: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """Noise, NLOS bias and dropouts of a batch of exchanges.

    Parameters
    ----------
    true_range_m : ndarray, shape (N,)
        True tag-anchor distances, m.
    cfg : UwbCfg
        Error parameters.
    rng : numpy.random.Generator
        Draws, in this order: N uniforms (dropout), N uniforms (NLOS), N
        exponentials (NLOS bias), N normals (noise); with ``blocked``, then N
        exponentials (blocked bias) and N uniforms (blocked dropout).
    blocked : ndarray of bool, shape (N,), optional
        Exchanges whose direct path a wall blocks (``blocked_bias_m``, ``blocked_dropout_prob``).

    Returns
    -------
    range_m : ndarray, shape (N,)
        Measured ranges (>= 0), m.
    received : ndarray of bool, shape (N,)
        False for a dropped exchange or a distance beyond ``max_range_m``.
    """
    d = np.asarray(true_range_m, dtype=np.float64)
    n = d.shape[0]
    u_drop, u_nlos = rng.random(n), rng.random(n)
    bias = rng.exponential(cfg.nlos_bias_m, n) if cfg.nlos_bias_m > 0 else np.zeros(n)
    noise = cfg.range_noise_sigma_m * rng.standard_normal(n)
    r = d + noise + np.where(u_nlos < cfg.nlos_prob, bias, 0.0)
    received = (u_drop >= cfg.dropout_prob) & (d <= cfg.max_range_m)
    if blocked is not None:
        wall = rng.exponential(cfg.blocked_bias_m, n) if cfg.blocked_bias_m > 0 else np.zeros(n)
        u_wall = rng.random(n)
        blocked = np.asarray(blocked, dtype=bool)
        r = r + np.where(blocked, wall, 0.0)
        received &= ~(blocked & (u_wall < cfg.blocked_dropout_prob))
    return np.maximum(r, 0.0), received


def corrupt_range(
    d_m: float, cfg: UwbCfg, rng: np.random.Generator, blocked: bool | None = None
) -> tuple[float, bool]:
    """One exchange of :func:`corrupt_ranges` (the same draws in the same order, the same sums): the
    sensor's path at 60 Hz, where NumPy's per-call cost on arrays of one dominated. Returns
    ``(range_m, received)``."""
    u_drop, u_nlos = rng.random(), rng.random()
    bias = rng.exponential(cfg.nlos_bias_m) if cfg.nlos_bias_m > 0 else 0.0
    noise = cfg.range_noise_sigma_m * rng.standard_normal()
    r = d_m + noise + (bias if u_nlos < cfg.nlos_prob else 0.0)
    received = u_drop >= cfg.dropout_prob and d_m <= cfg.max_range_m
    if blocked is not None:
        wall = rng.exponential(cfg.blocked_bias_m) if cfg.blocked_bias_m > 0 else 0.0
        u_wall = rng.random()
        r = r + (wall if blocked else 0.0)
        received = received and not (blocked and u_wall < cfg.blocked_dropout_prob)
    return max(r, 0.0), bool(received)
