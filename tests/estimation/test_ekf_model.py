"""The EKF's motion and measurement models against finite differences (no mujoco)."""

import math

import numpy as np
import pytest

from amr_twin.model.config import load_config
from amr_twin.estimation.ekf_model import (
    N_STATE,
    W,
    YAW,
    predict_mean,
    process_noise,
    range_model,
    transition_jacobian,
)

STATES = [
    np.array([1.0, -2.0, 0.3, 0.8, 0.5, 0.01]),
    np.array([-3.0, 4.0, 3.1, -0.4, -1.2, -0.02]),
    np.array([0.0, 0.0, -1.5, 0.0, 0.0, 0.0]),
]


def _predicted(x: np.ndarray, dt_s: float) -> np.ndarray:
    col = x.reshape(-1, 1).copy()
    predict_mean(col, dt_s)
    return col.ravel()


@pytest.mark.parametrize("x", STATES)
def test_transition_jacobian_matches_finite_differences(x):
    dt_s, eps = 0.02, 1e-6
    F = transition_jacobian(x, dt_s)
    numeric = np.column_stack(
        [
            (_predicted(x + eps * e, dt_s) - _predicted(x - eps * e, dt_s)) / (2 * eps)
            for e in np.eye(N_STATE)
        ]
    )
    np.testing.assert_allclose(F, numeric, atol=1e-8)


def test_constant_turn_rate_arc():
    x = np.array([0.0, 0.0, 0.0, 1.0, 0.5, 0.0])  # 1 m/s, 0.5 rad/s for 0.1 s
    y = _predicted(x, 0.1)
    assert y[YAW] == pytest.approx(0.05)
    assert y[0] == pytest.approx(0.1 * math.cos(0.025)) and y[1] == pytest.approx(
        0.1 * math.sin(0.025)
    )
    assert y[W] == 0.5  # velocities are held


@pytest.mark.parametrize("x", STATES)
def test_range_jacobian_matches_finite_differences(x):
    anchor, tag, dz = np.array([9.5, 6.5]), np.array([-0.30, 0.0]), 2.05
    r, H = range_model(x, anchor, tag, dz)
    c, s = math.cos(x[YAW]), math.sin(x[YAW])
    tag_world = x[:2] + np.array([c * tag[0] - s * tag[1], s * tag[0] + c * tag[1]])
    assert r == pytest.approx(math.sqrt(np.sum((anchor - tag_world) ** 2) + dz * dz))
    eps = 1e-6
    numeric = [
        (
            range_model(x + eps * e, anchor, tag, dz)[0]
            - range_model(x - eps * e, anchor, tag, dz)[0]
        )
        / (2 * eps)
        for e in np.eye(N_STATE)
    ]
    np.testing.assert_allclose(np.ravel(H), numeric, atol=1e-7)


def test_process_noise_is_symmetric_positive_semidefinite_and_grows_with_dt():
    cfg = load_config().ekf
    x = STATES[0]
    q1, q2 = process_noise(x, 0.01, cfg), process_noise(x, 0.1, cfg)
    for q in (q1, q2):
        np.testing.assert_allclose(q, q.T, atol=0)
        assert np.linalg.eigvalsh(q).min() > -1e-15
    assert np.trace(q2) > np.trace(q1)
