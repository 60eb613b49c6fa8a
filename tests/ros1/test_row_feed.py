"""The bridge's 100 Hz rows (amr_twin/ros1/row_feed.py) are the recorder's series, bit for bit,
taken in pieces, and keep the twin's grid loop in C (no ROS 1 needed)."""

import numpy as np
import pytest

from amr_twin.model.config import load_config
from amr_twin.ros1.row_feed import RowFeed
from amr_twin.sim.plant import MODE_CODES
from amr_twin.assembly.twin import Twin, TwinOptions
from amr_twin.assembly.command import Command
from amr_twin.recording.recorder import attach_recorder, recorder_of


@pytest.mark.parametrize("piece_us", [20_000, 400_000, 130_000])
def test_the_rows_are_the_recorders_series(piece_us):
    twin = Twin(load_config(), TwinOptions(world="empty", sensors=("imu", "lidar")))
    attach_recorder(twin)
    feed = RowFeed(twin)
    got = []
    for t_us, command in (
        (0, Command("linear", speed_m_s=0.6)),
        (1_500_000, Command("stop")),
        (2_300_000, Command("angular", speed_deg_s=40.0)),
    ):
        while twin.clock.now_us < t_us:
            twin.advance(piece_us * 1e-6)
            got.append(feed.take(twin.clock.now_us))
        command.send(twin)
    twin.advance(1.0)
    got.append(feed.take(twin.clock.now_us))
    got = [g for g in got if g is not None]
    t_us = np.concatenate([g.t_us for g in got])
    series = recorder_of(twin).series()
    k = np.searchsorted(np.round(series.t_s * 1e6).astype(np.int64), t_us)
    assert len(t_us) >= 300 and np.array_equal(np.round(series.t_s[k] * 1e6), t_us)
    assert t_us[0] == 0 and np.array_equal(
        np.concatenate([g.index for g in got]), np.arange(len(t_us))
    )
    for name in ("true_rpm", "pwm_counts", "current_a", "battery_v", "battery_a", "battery_soc"):
        assert np.array_equal(
            np.concatenate([getattr(g, name) for g in got]), getattr(series, name)[k]
        ), name
    assert (
        np.abs(series.current_a[k]).max() > 0.5 and np.ptp(series.pwm_counts[k]) > 0
    )  # the drive changed


def test_the_grid_loop_stays_in_c():
    twin = Twin(load_config(), TwinOptions(world="empty", sensors=("imu", "lidar")))
    attach_recorder(twin)
    grid = twin._grid
    if grid._stepper is None:
        pytest.skip("no C compiler: the grid loop runs in Python for every twin")
    assert grid._stepper.use(grid.samplers)
    RowFeed(twin)
    assert grid._stepper.use(grid.samplers)


def _random_raw(rng, grid_us=10_000):
    n, m, nb = int(rng.integers(1, 60)), int(rng.integers(1, 20)), int(rng.integers(1, 80))
    times = np.sort(rng.choice(np.arange(0, 3_000) * grid_us, n, replace=False)).astype(np.int64)
    times[rng.random(n) < 0.1] += 7  # off the grid
    times.sort()
    rows = rng.normal(0, 1, (n, 9)) * 10.0 ** rng.integers(-9, 6, (n, 9))
    rows[rng.random((n, 9)) < 0.15] = 0.0
    rows[rng.random((n, 9)) < 0.15] = -0.0
    pin_t = np.sort(rng.integers(times[0] - grid_us, times[-1] + grid_us, m)).astype(np.int64)
    pin_t[0] = min(pin_t[0], times[0])
    pins = np.column_stack(
        [
            rng.uniform(-300, 300, (m, 2)),
            rng.choice([-1.0, 1.0], (m, 2)),
            rng.choice([float(c) for c in MODE_CODES.values()], (m, 2)),
            rng.normal(0, 8, (m, 2)) * 10.0 ** rng.integers(-6, 3, (m, 2)),
        ]
    )
    pins[:, 6:8][rng.random((m, 2)) < 0.2] = -0.0
    bat_t = np.sort(rng.integers(times[0] - grid_us, times[-1] + 2, nb)).astype(float)
    battery = np.column_stack(
        [bat_t, rng.uniform(10, 13, nb), rng.normal(0, 3, nb), rng.random(nb)]
    )
    battery[:, 2][rng.random(nb) < 0.2] = -0.0
    return times, rows, pin_t, pins, battery


def test_the_c_blocks_are_the_python_twins_bytes():
    twin = Twin(load_config(), TwinOptions(world="empty"))
    c_feed, py_feed = RowFeed(twin), RowFeed(twin, native=False)
    if c_feed.engine != "C":
        pytest.skip(f"no C helper: {c_feed.engine}")
    assert py_feed.engine.startswith("Python")
    rng = np.random.default_rng(7)
    fields = ("t_us", "true_rpm", "pwm_counts", "current_a", "battery_us", "battery")
    for _ in range(200):
        raw = _random_raw(rng)
        got = c_feed._blocks_native(*raw)
        want = py_feed._blocks_python(py_feed._columns(*raw))
        assert [getattr(got, f) for f in fields] == [getattr(want, f) for f in fields]
        assert np.array_equal(got.battery_rows, want.battery_rows)
    Command("linear", speed_m_s=0.6).send(twin)  # and a run's rows, taken by both
    for _ in range(10):
        twin.advance(0.13)
        got, want = c_feed.blocks(twin.clock.now_us), py_feed.blocks(twin.clock.now_us)
        assert [getattr(got, f) for f in fields] == [getattr(want, f) for f in fields]
        assert len(got.t_us) >= 13 and np.array_equal(got.battery_rows, want.battery_rows)
