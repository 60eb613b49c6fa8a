"""The bridge's 100 Hz rows (amr_twin/ros1/row_feed.py) are the recorder's series, bit for bit,
taken in pieces, and keep the twin's grid loop in C (no ROS 1 needed)."""

import numpy as np
import pytest

from amr_twin.model.config import load_config
from amr_twin.ros1.row_feed import RowFeed
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
