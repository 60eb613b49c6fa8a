"""The IMU's error stream: batches of any size give the per-sample numbers; C against numpy, to the
bit."""

import shutil

import numpy as np
import pytest

from amr_twin.model.config import load_config
from amr_twin.sensors.imu_errors import ERROR_BLOCK, AxisModel, ErrorStream, axis_models, corrupt

HAVE_CC = shutil.which("cc") is not None or shutil.which("gcc") is not None
SCALES = np.array([1, 1, 10, 0.1, 0.1, 0.1, 4e-5, 4e-5, 4e-5])


def _stream(seed: int, native: bool, cfg=None) -> ErrorStream:
    cfg = cfg or load_config().imu
    rng = np.random.default_rng(seed)
    return ErrorStream(axis_models(cfg, rng), 0.01, rng, native)


def _true(n: int, seed: int = 0) -> np.ndarray:
    true = np.random.default_rng(seed).normal(0.0, 1.0, (n, 9)) * SCALES
    true[::13] *= 1e4  # past every range: saturated
    return true


@pytest.mark.parametrize(
    "native",
    [False, pytest.param(True, marks=pytest.mark.skipif(not HAVE_CC, reason="no C compiler"))],
)
def test_batches_across_blocks_draw_the_per_sample_numbers(native):
    n = 2 * ERROR_BLOCK + 100
    true = _true(n)
    one, many = _stream(4, native), _stream(4, native)
    single = np.concatenate([one.corrupt_batch(true[i : i + 1]) for i in range(n)])
    cuts = np.cumsum(np.random.default_rng(1).integers(1, 40, n))
    cuts = [0, *cuts[cuts < n].tolist(), n]
    batched = np.concatenate([many.corrupt_batch(true[a:b]) for a, b in zip(cuts[:-1], cuts[1:])])
    batched = np.concatenate(
        [batched, many.corrupt_batch(true[: 0 + 300])]
    )  # a batch larger than a block
    single = np.concatenate([single, *(one.corrupt_batch(true[i : i + 1]) for i in range(300))])
    assert single.tobytes() == batched.tobytes()
    assert one.bias.tobytes() == many.bias.tobytes()
    assert not np.array_equal(one.bias, _stream(4, native).bias)  # it walked


@pytest.mark.skipif(not HAVE_CC, reason="no C compiler")
@pytest.mark.parametrize("seed", [0, 7])
def test_c_helper_and_python_twin_give_the_same_bits(seed):
    c, py = _stream(seed, True), _stream(seed, False)
    assert c.engine == "C" and py.engine == "Python (native=False)"
    true = _true(700, seed)
    out_c = np.concatenate([c.corrupt_batch(true[i : i + 23]) for i in range(0, 700, 23)])
    out_py = np.concatenate([py.corrupt_batch(true[i : i + 23]) for i in range(0, 700, 23)])
    assert out_c.tobytes() == out_py.tobytes()
    ranges, half_step = c._range, np.where(c._quantised, c._res / 2, 0.0) * (1 + 1e-9)
    assert np.all(np.abs(out_c) <= ranges + half_step)  # clipped, then quantised
    assert np.any(np.abs(out_c) >= ranges - half_step)  # the saturated ones at the limit
    res = c._res[c._quantised]
    q = out_c[:, c._quantised] / res
    assert np.allclose(q, np.round(q), atol=1e-6)  # quantised axes on their resolution


@pytest.mark.parametrize("dt_s", [0.01, 0.0025])
def test_bias_random_walk_spreads_as_the_square_root_of_time(dt_s):
    """A bias random walk of density q (unit / sqrt(s)) takes steps of q sqrt(dt), so that after t
    seconds it has spread q sqrt(t) whatever the sample period (steps of q dt once survived
    the suite). Noise, scale and turn-on bias off, so each reading is the bias itself; 4 s on 9
    axes and 3 seeds: the steps' spread is known to 0.6 %, the tolerance is 5 %."""
    q, n = 2.0, int(round(4.0 / dt_s))
    for seed in (0, 1, 2):
        models = {
            k: AxisModel(np.zeros(3), np.zeros(3), 0.0, q, 1e12, np.zeros(3))
            for k in ("accel", "gyro", "mag")
        }
        stream = ErrorStream(models, dt_s, np.random.default_rng(seed), native=False)
        bias = stream.corrupt_batch(np.zeros((n, 9)))
        assert np.std(np.diff(bias, axis=0)) == pytest.approx(q * np.sqrt(dt_s), rel=0.05)
        one = AxisModel(np.zeros(3), np.zeros(3), 0.0, q, 1e12, np.zeros(3))
        rng = np.random.default_rng(seed)
        walk = np.array([corrupt(np.zeros(3), one, rng, dt_s) for _ in range(n)])
        assert np.std(np.diff(walk, axis=0)) == pytest.approx(q * np.sqrt(dt_s), rel=0.05)
