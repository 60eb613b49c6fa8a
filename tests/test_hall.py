"""Hall sensors and SC output: 90 changes per revolution, both directions, vectorised."""


import numpy as np
import pytest


from amr_twin.sensors.hall import HallSensors

A0_RAD = 0.123  # start angle off the sensor lattices


def one_revolution(rpm: float, sign: int, step_us: int = 1000):
    """Two wheels turning one revolution at ``rpm``, sampled every ``step_us``."""
    duration_us = int(round(60e6 / rpm))
    t_us = np.arange(0, duration_us + step_us, step_us, dtype=np.int64)
    frac = np.minimum(t_us / duration_us, 1.0)
    angle = A0_RAD + sign * 2 * np.pi * frac
    return t_us, np.column_stack([angle, 0.5 * angle])


@pytest.mark.parametrize("rpm", [10.0, 76.39, 200.0])
@pytest.mark.parametrize("sign", [1, -1])
def test_ninety_changes_per_revolution(rpm, sign):
    hall = HallSensors()
    t_us, angle = one_revolution(rpm, sign)
    hall.reset(angle[0])
    edge_t, edge_w = hall.edges(t_us, angle)
    assert np.sum(edge_w == 0) == 90
    assert np.sum(edge_w == 1) == 45  # half a revolution
    assert np.all(np.diff(edge_t) >= 0)
    assert edge_t[0] > t_us[0] and edge_t[-1] <= t_us[-1]
    period_us = np.diff(edge_t[edge_w == 0])
    expected_us = 60e6 / (90 * rpm)
    assert np.all(np.abs(period_us - expected_us) <= 1.5)


def test_chunks_give_the_same_edges_as_one_call():
    t_us, angle = one_revolution(76.39, 1)
    whole = HallSensors().edges(t_us, angle)
    hall = HallSensors()
    parts = [hall.edges(t_us[i:i + 101], angle[i:i + 101]) for i in range(0, len(t_us) - 1, 100)]
    np.testing.assert_array_equal(whole[0], np.concatenate([p[0] for p in parts]))
    np.testing.assert_array_equal(whole[1], np.concatenate([p[1] for p in parts]))


def test_back_and_forth_returns_to_the_same_states_and_sc_parity():
    hall = HallSensors()
    t_us = np.arange(0, 2_000_001, 1000, dtype=np.int64)
    swing = A0_RAD + 0.6 * np.sin(2 * np.pi * t_us / 1e6)  # +-34 degrees, two periods
    angle = np.column_stack([swing, -swing])
    hall.reset(angle[0])
    states0, sc0 = hall.states.copy(), hall.sc_level.copy()
    edge_t, edge_w = hall.edges(t_us, angle)
    np.testing.assert_array_equal(hall.states, states0)
    # 0.6 rad = 34.4 deg -> 8 or 9 crossings each way, 4 sweeps per period, 2 periods
    n0 = np.sum(edge_w == 0)
    assert n0 % 2 == 0 and 60 <= n0 <= 76
    np.testing.assert_array_equal(hall.sc_level, sc0)


def test_sc_level_toggles_on_every_edge():
    hall = HallSensors(n_wheels=1)
    t_us = np.array([0, 1000], dtype=np.int64)
    hall.reset([A0_RAD])
    levels = [int(hall.sc_level[0])]
    for k in range(1, 40):
        a = A0_RAD + np.deg2rad(4.0) * k
        hall.edges(t_us + 1000 * k, np.array([[a - np.deg2rad(4.0)], [a]]))
        levels.append(int(hall.sc_level[0]))
    assert all(x != y for x, y in zip(levels, levels[1:]))


def test_misalignment_keeps_count_but_not_spacing():
    hall = HallSensors(misalignment_deg=[0.0, 1.0, -0.5])
    t_us, angle = one_revolution(60.0, 1)
    edge_t, edge_w = hall.edges(t_us, angle)
    assert np.sum(edge_w == 0) == 90
    period_us = np.diff(edge_t[edge_w == 0])
    assert period_us.max() - period_us.min() > 2000  # 1 degree at 60 RPM = 2.8 ms


def test_jitter_is_seeded_sorted_and_inside_the_chunk():
    t_us, angle = one_revolution(76.39, 1)
    a = HallSensors(jitter_us=50.0, seed=7).edges(t_us, angle)
    b = HallSensors(jitter_us=50.0, seed=7).edges(t_us, angle)
    clean = HallSensors().edges(t_us, angle)
    np.testing.assert_array_equal(a[0], b[0])
    assert np.all(np.diff(a[0]) >= 0)
    assert a[0][0] > t_us[0] and a[0][-1] <= t_us[-1]
    assert 10 < np.std(np.sort(a[0][a[1] == 0]) - clean[0][clean[1] == 0]) < 100
