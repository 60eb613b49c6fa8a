"""UWB error model: exact without errors, one exchange as a batch of one, the noise, dropout and
NLOS statistics."""

import numpy as np
import pytest

from amr_twin.model.config import load_config
from amr_twin.sensors.uwb_errors import corrupt_range, corrupt_ranges


def _cfg(**values):
    return load_config(overrides={f"uwb.{k}": v for k, v in values.items()}).uwb


def test_exact_ranges_without_errors():
    cfg = _cfg(range_noise_sigma_m=0.0, nlos_prob=0.0, dropout_prob=0.0)
    d = np.array([1.0, 5.0, 39.0, 41.0])
    r, ok = corrupt_ranges(d, cfg, np.random.default_rng(0))
    assert r.tolist() == d.tolist()
    assert ok.tolist() == [True, True, True, False]  # beyond max_range_m (40 m)


@pytest.mark.parametrize("walls", [False, True])
def test_one_exchange_draws_as_a_batch_of_one(walls):
    cfg = _cfg(
        range_noise_sigma_m=0.05,
        nlos_prob=0.3,
        nlos_bias_m=0.4,
        dropout_prob=0.2,
        blocked_bias_m=0.6,
        blocked_dropout_prob=0.5,
    )
    one, batch, rng_d = np.random.default_rng(3), np.random.default_rng(3), np.random.default_rng(4)
    seen = set()
    for _ in range(400):
        d, blocked = rng_d.uniform(0.0, 45.0), (bool(rng_d.random() < 0.5) if walls else None)
        r, ok = corrupt_range(d, cfg, one, blocked)
        rb, okb = corrupt_ranges(
            np.array([d]), cfg, batch, None if blocked is None else np.array([blocked])
        )
        assert (r, ok) == (rb[0], okb[0])
        seen.add(ok)
    assert seen == {True, False}


def test_noise_and_dropout_statistics():
    cfg = _cfg(range_noise_sigma_m=0.05, nlos_prob=0.0, dropout_prob=0.1)
    d = np.full(20000, 8.0)
    r, ok = corrupt_ranges(d, cfg, np.random.default_rng(1))
    assert abs(1.0 - ok.mean() - 0.1) < 0.01
    assert abs(np.mean(r - d)) < 0.002 and abs(np.std(r - d) - 0.05) < 0.002


def test_nlos_bias_is_positive_and_exponential():
    cfg = _cfg(range_noise_sigma_m=0.0, nlos_prob=0.2, nlos_bias_m=0.5, dropout_prob=0.0)
    d = np.full(20000, 8.0)
    err = corrupt_ranges(d, cfg, np.random.default_rng(1))[0] - d
    assert np.all(err >= 0.0)
    assert abs(np.mean(err > 0) - 0.2) < 0.01
    assert abs(np.mean(err[err > 0]) - 0.5) < 0.03
