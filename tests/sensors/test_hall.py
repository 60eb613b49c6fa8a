"""Hall sensors and SC output: 90 changes per revolution, both directions, vectorised."""

import shutil

import numpy as np
import pytest


from amr_twin.model.config import load_config
from amr_twin.sensors.hall import HallSensors

POLE_PAIRS = load_config().wheel.hall_pole_pairs

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
    hall = HallSensors(pole_pairs=POLE_PAIRS)
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
    whole = HallSensors(pole_pairs=POLE_PAIRS).edges(t_us, angle)
    hall = HallSensors(pole_pairs=POLE_PAIRS)
    parts = [
        hall.edges(t_us[i : i + 101], angle[i : i + 101]) for i in range(0, len(t_us) - 1, 100)
    ]
    np.testing.assert_array_equal(whole[0], np.concatenate([p[0] for p in parts]))
    np.testing.assert_array_equal(whole[1], np.concatenate([p[1] for p in parts]))


def test_back_and_forth_returns_to_the_same_states_and_sc_parity():
    hall = HallSensors(pole_pairs=POLE_PAIRS)
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
    hall = HallSensors(pole_pairs=POLE_PAIRS, n_wheels=1)
    t_us = np.array([0, 1000], dtype=np.int64)
    hall.reset([A0_RAD])
    levels = [int(hall.sc_level[0])]
    for k in range(1, 40):
        a = A0_RAD + np.deg2rad(4.0) * k
        hall.edges(t_us + 1000 * k, np.array([[a - np.deg2rad(4.0)], [a]]))
        levels.append(int(hall.sc_level[0]))
    assert all(x != y for x, y in zip(levels, levels[1:]))


def test_misalignment_keeps_count_but_not_spacing():
    hall = HallSensors(pole_pairs=POLE_PAIRS, misalignment_deg=[0.0, 1.0, -0.5])
    t_us, angle = one_revolution(60.0, 1)
    edge_t, edge_w = hall.edges(t_us, angle)
    assert np.sum(edge_w == 0) == 90
    period_us = np.diff(edge_t[edge_w == 0])
    assert period_us.max() - period_us.min() > 2000  # 1 degree at 60 RPM = 2.8 ms


def test_jitter_is_seeded_sorted_and_inside_the_chunk():
    t_us, angle = one_revolution(76.39, 1)
    a = HallSensors(pole_pairs=POLE_PAIRS, jitter_us=50.0, seed=7).edges(t_us, angle)
    b = HallSensors(pole_pairs=POLE_PAIRS, jitter_us=50.0, seed=7).edges(t_us, angle)
    clean = HallSensors(pole_pairs=POLE_PAIRS).edges(t_us, angle)
    np.testing.assert_array_equal(a[0], b[0])
    assert np.all(np.diff(a[0]) >= 0)
    assert a[0][0] > t_us[0] and a[0][-1] <= t_us[-1]
    assert 10 < np.std(np.sort(a[0][a[1] == 0]) - clean[0][clean[1] == 0]) < 100


def _hermite(q0, q1, m0, m1, s):
    """The cubic Hermite interpolant in its textbook basis form (not the solver's power form)."""
    return (
        (2 * s**3 - 3 * s**2 + 1) * q0
        + (s**3 - 2 * s**2 + s) * m0
        + (-2 * s**3 + 3 * s**2) * q1
        + (s**3 - s**2) * m1
    )


def _bisect_edges(ts, rows, offsets, pitch):
    """Reference: every lattice crossing found by bisection on the cubic (60 halvings), rounded to
    the microsecond; crossings too close to a half microsecond to call are returned apart."""
    edges, ties = [], 0
    for w in range(2):
        for off in offsets[w]:
            for i in range(len(ts) - 1):
                q0, q1 = rows[i][w], rows[i + 1][w]
                h = (ts[i + 1] - ts[i]) * 1e-6
                m0, m1 = rows[i][2 + w] * h, rows[i + 1][2 + w] * h
                c0, c1 = np.floor((q0 - off) / pitch), np.floor((q1 - off) / pitch)
                lattices = (
                    range(int(c0) + 1, int(c1) + 1) if c1 > c0 else range(int(c0), int(c1), -1)
                )
                for lat in lattices:
                    theta = off + pitch * lat
                    lo, hi = 0.0, 1.0
                    rising = q1 > q0
                    for _ in range(60):
                        mid = 0.5 * (lo + hi)
                        if (_hermite(q0, q1, m0, m1, mid) < theta) == rising:
                            lo = mid
                        else:
                            hi = mid
                    t = ts[i] + lo * (ts[i + 1] - ts[i])
                    if abs(t - np.floor(t) - 0.5) < 1e-6:
                        ties += 1
                        continue
                    edges.append((min(ts[-1], max(ts[0] + 1, int(round(t)))), w))
    return sorted(edges), ties


@pytest.mark.parametrize("seed", range(6))
def test_edge_times_are_the_cubics_roots_to_the_microsecond(seed):
    """edges_from_samples (Newton on the power form, early stop) against bisection on the basis
    form: the same integer edge times on monotonic chunks of 10 ms samples at 20-250 RPM,
    accelerating and decelerating, with misaligned sensors."""
    rng = np.random.default_rng(seed)
    hall = HallSensors(pole_pairs=POLE_PAIRS, misalignment_deg=rng.uniform(-0.5, 0.5, (2, 3)))
    n = 12
    ts = (np.arange(n + 1) * 10_000 + 1_000_000).tolist()
    speed = rng.uniform(2.0, 26.0, 2) * rng.choice([-1, 1], 2)  # rad/s, 20-250 RPM, either sign
    accel = (
        rng.uniform(-0.4, 0.4, 2) * np.abs(speed) / 0.12
    )  # +-40 % over the chunk, no sign change
    t_s = (np.array(ts) - ts[0]) * 1e-6
    q = rng.uniform(0, 6, 2) + speed * t_s[:, None] + 0.5 * accel * t_s[:, None] ** 2
    v = speed + accel * t_s[:, None]
    rows = np.hstack([q, v]).tolist()
    hall.reset(q[0])
    got = hall.edges_from_samples(ts, rows)
    want, ties = _bisect_edges(ts, rows, hall.offset_rad.tolist(), hall.pitch_rad)
    assert len(got) >= 10 and ties == 0
    assert sorted(got) == want


@pytest.mark.skipif(
    shutil.which("cc") is None and shutil.which("gcc") is None, reason="no C compiler"
)
@pytest.mark.parametrize("seed, hysteresis_deg", [(0, 0.0), (1, 0.0), (2, 0.3), (3, 0.3)])
def test_c_crossing_loop_gives_the_python_twins_edges_and_counts(seed, hysteresis_deg):
    """Random chunks (both directions, a speed changing sign, a stuck sensor, a long fast chunk)."""
    rng = np.random.default_rng(seed)
    mis = rng.uniform(-0.5, 0.5, (2, 3))
    c = HallSensors(pole_pairs=POLE_PAIRS, misalignment_deg=mis, hysteresis_deg=hysteresis_deg)
    py = HallSensors(
        pole_pairs=POLE_PAIRS, misalignment_deg=mis, native=False, hysteresis_deg=hysteresis_deg
    )
    assert c.engine == "C" and py.engine == "Python (native=False)"
    for chunk in range(30):
        n = int(rng.integers(1, 40))
        ts = np.cumsum(np.r_[1_000_000 + chunk * 500_000, rng.integers(1_000, 10_001, n)]).tolist()
        t_s = (np.array(ts) - ts[0]) * 1e-6
        speed, accel = rng.uniform(-40.0, 40.0, 2), rng.uniform(-200.0, 200.0, 2)
        q = rng.uniform(-50, 50, 2) + speed * t_s[:, None] + 0.5 * accel * t_s[:, None] ** 2
        rows = np.hstack(
            [q, speed + accel * t_s[:, None], rng.normal(size=(n + 1, 3))]
        ).tolist()  # extra columns
        wheel, sensor = int(rng.integers(0, 2)), int(rng.integers(0, 3))
        for h in (c, py):
            h.reset(q[0])
            h.set_stuck(wheel, sensor, chunk % 3 == 0, float(q[0, wheel]))
        got, want = c.edges_from_samples(ts, rows), py.edges_from_samples(ts, rows)
        assert got == want and np.array_equal(c._count, py._count)
    assert len(want) > 0


def _spring_back(hall: HallSensors) -> list:
    """A wheel rolling forward that stops 0.12 deg past a boundary (at 4 deg) and springs back
    0.15 deg, sampled every 10 ms (angle and speed: a cosine stop, then a cosine return)."""
    stop, back = np.radians(4.12), np.radians(0.15)
    t = np.arange(0, 0.400001, 0.01)
    q = np.where(
        t < 0.2,
        stop - np.radians(2.0) * (1 + np.cos(np.pi * t / 0.2)) / 2,
        stop - back * (1 - np.cos(np.pi * (t - 0.2) / 0.2)) / 2,
    )
    v = np.where(
        t < 0.2,
        np.radians(2.0) * np.pi / 0.4 * np.sin(np.pi * t / 0.2),
        -back * np.pi / 0.4 * np.sin(np.pi * (t - 0.2) / 0.2),
    )
    q, v = np.column_stack([q, q]), np.column_stack([v, v])
    hall.reset(q[0])
    return hall.edges_from_samples(
        (t * 1e6).round().astype(int).tolist(), np.hstack([q, v]).tolist()
    )


@pytest.mark.parametrize("native", [True, False])
def test_the_latches_hysteresis_keeps_a_wheel_springing_back_from_toggling_again(native):
    """Without hysteresis the sensor passed at 4 deg toggles back (two SC changes, which a counter
    without direction takes for two edges of travel); with a 0.2 deg band it toggled at 4.1 deg and
    the wheel, back to 3.97 deg, stays inside the band (one change each wheel)."""
    plain = _spring_back(HallSensors(pole_pairs=POLE_PAIRS, n_wheels=2, native=native))
    latch = _spring_back(
        HallSensors(pole_pairs=POLE_PAIRS, n_wheels=2, native=native, hysteresis_deg=0.2)
    )
    assert len(plain) == 4 and len(latch) == 2 and {w for _, w in latch} == {0, 1}


def test_hysteresis_shifts_steady_edges_by_half_the_band_and_keeps_their_spacing():
    w = 2.0  # rad/s
    t = np.arange(0, 0.5, 0.01)
    rows = np.column_stack([0.01 + w * t, np.full_like(t, w)]).tolist()
    ts = (t * 1e6).round().astype(int).tolist()
    found = []
    for band in (0.0, 0.4):
        hall = HallSensors(pole_pairs=POLE_PAIRS, n_wheels=1, hysteresis_deg=band)
        hall.reset([0.01])
        found.append(np.array([e for e, _ in hall.edges_from_samples(ts, rows)]))
    plain, shifted = found
    assert len(plain) == len(shifted) > 10
    assert np.allclose(shifted - plain, np.radians(0.2) / w * 1e6, atol=1.0)


@pytest.mark.parametrize("native", [True, False])
def test_a_latch_remembers_its_state_from_one_chunk_to_the_next(native):
    """A wheel that stops inside the band (4.05 deg: past the boundary at 4, short of the 4.1 where
    the latch toggles), then, in the loop's next chunk, rolls on to 4.5 deg: one change, at 4.1."""
    hall = HallSensors(pole_pairs=POLE_PAIRS, n_wheels=1, native=native, hysteresis_deg=0.2)
    hall.reset([0.0])
    w = np.radians(2.0)  # rad/s
    first = hall.edges_from_samples(
        [0, 1_000_000, 2_025_000], [[0.0, w], [w, w], [np.radians(4.05), 0.0]]
    )
    second = hall.edges_from_samples(
        [2_025_000, 3_000_000, 4_000_000],
        [[np.radians(4.05), 0.0], [np.radians(4.3), w], [np.radians(4.5), 0.0]],
    )
    assert first == [] and len(second) == 1
