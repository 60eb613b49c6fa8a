"""The fleet measures on made-up fleets of 2-4 robots: time on orders, near misses, where
throughput saturates, energy by payload bin."""

import numpy as np
import pytest

from amr_twin.experiments.fleet import metrics


def _events():
    return [
        {"t_s": 0.0, "event": "placed", "vehicle": "amr-1"},
        {"t_s": 10.0, "event": "assigned", "vehicle": "amr-1", "task": "job", "job": "job-1"},
        {"t_s": 12.0, "event": "assigned", "vehicle": "amr-2", "task": "job", "job": "job-2"},
        {"t_s": 15.0, "event": "assigned", "vehicle": "amr-3", "task": "charge"},
        {"t_s": 40.0, "event": "done", "vehicle": "amr-1", "task": "job", "job": "job-1"},
        {"t_s": 50.0, "event": "done", "vehicle": "amr-3", "task": "charge"},
        {"t_s": 52.0, "event": "failed", "vehicle": "amr-2", "task": "job", "job": "job-2"},
        {"t_s": 60.0, "event": "assigned", "vehicle": "amr-1", "task": "job", "job": "job-3"},
    ]


def test_time_on_orders_per_robot_counts_jobs_only_and_clips_an_open_one():
    ev = _events()
    spans = {s: metrics.busy_intervals(ev, s, 100.0) for s in ("amr-1", "amr-2", "amr-3")}
    assert spans["amr-1"] == [(10.0, 40.0), (60.0, 100.0)]
    assert spans["amr-2"] == [(12.0, 52.0)]
    assert spans["amr-3"] == []  # charging is no order
    util = [metrics.utilisation(spans[s], 100.0) for s in sorted(spans)]
    assert util == pytest.approx([0.7, 0.4, 0.0])


def test_near_misses_are_episodes_per_pair_with_their_least_distance():
    near = metrics.NearMisses(1.2)
    for k in range(21):
        t = k * 0.1
        x = -5.0 + 0.5 * k  # amr-2 drives past amr-1 at (0, 0.8) at t = 1.0
        near.update(
            t,
            {
                "amr-1": (0.0, 0.8),
                "amr-2": (x, 0.0),
                "amr-3": (20.0, 0.0),
                "amr-4": (20.0, 0.0 if k in (3, 4, 9) else 5.0),  # two dips under amr-3
            },
        )
    pairs = [tuple(e["robots"]) for e in near.episodes]
    assert pairs == [("amr-3", "amr-4"), ("amr-1", "amr-2"), ("amr-3", "amr-4")]
    passing = near.episodes[1]
    assert passing["least_m"] == pytest.approx(0.8) and passing["least_t_s"] == pytest.approx(1.0)
    assert near.least_m == pytest.approx(0.0)


@pytest.mark.parametrize(
    "throughputs, expected",
    [
        ([55.0, 110.0, 200.0, 210.0], 4),  # 4 -> 8 robots adds 5 %
        ([55.0, 58.0, 200.0, 400.0], 1),  # 1 -> 2 adds 5.5 %: the first flat step counts
        ([55.0, 110.0, 200.0, 400.0], None),
        ([55.0, 110.0, 200.0, 219.0], 4),  # 9.5 %: under 10 %
        ([55.0, 110.0, 200.0, 221.0], None),  # 10.5 %
    ],
)
def test_saturation_is_the_fleet_size_after_which_throughput_rises_under_ten_percent(
    throughputs, expected
):
    assert metrics.saturation([8, 4, 2, 1], throughputs[::-1]) == expected


def test_energy_between_interpolates_a_cumulative_series():
    t = np.array([0.0, 1.0, 2.0, 3.0])
    e = np.array([0.0, 10.0, 30.0, 60.0])
    assert metrics.energy_between(t, e, 0.5, 2.5) == pytest.approx(45.0 - 5.0)


def test_payload_bins_split_orders_and_give_energy_per_order_and_per_km():
    jobs = [
        {"payload_kg": 2.0, "energy_wh": 1.0, "driving_wh": 0.5, "distance_m": 40.0},
        {"payload_kg": 8.0, "energy_wh": 3.0, "driving_wh": 1.5, "distance_m": 40.0},
        {"payload_kg": 25.0, "energy_wh": 2.0, "driving_wh": 1.0, "distance_m": 20.0},
        {"payload_kg": 30.0, "energy_wh": 4.0, "driving_wh": 2.0, "distance_m": 20.0},
    ]
    bins = metrics.payload_bins(jobs, metrics.bin_edges(0.0, 30.0))
    assert [b["orders"] for b in bins] == [2, 0, 2]  # 30 kg falls in the last bin
    assert bins[0]["energy_wh_median"] == 2.0 and bins[0]["driving_wh_per_km_median"] == 25.0
    assert bins[1]["energy_wh_median"] is None
    assert bins[2]["driving_wh_per_km_median"] == 75.0
    assert metrics.percentiles([]) == [None, None]


def test_the_payload_line_recovers_a_made_up_cost_per_kg():
    jobs = [
        {"payload_kg": kg, "driving_wh": (10.0 + 0.2 * kg) * d / 1000, "distance_m": d}
        for kg, d in ((0.0, 30.0), (10.0, 45.0), (25.0, 20.0), (40.0, 36.0))
    ]
    fit = metrics.payload_slope(jobs)
    assert fit == {"orders": 4, "wh_per_km_at_0kg": 10.0, "wh_per_km_per_10kg": 2.0}
    assert metrics.payload_slope(jobs[:2]) is None
