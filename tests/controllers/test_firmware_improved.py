"""Improved firmware: per-edge speed, 50 Hz PI with anti-windup, two-way ramp; vs faithful."""

import math
from dataclasses import replace

import numpy as np
from wheel_model import WHEEL, K_RPM, TAU_S, simulate  # noqa: F401
import pytest


from amr_twin.base.clock import VirtualClock
from amr_twin.base.pins import HIGH, LOW
from amr_twin.controllers.firmware import BoardParams, ImprovedParams, make_firmware

LOG = ImprovedParams(board=BoardParams(record_pin_log=True))


def make(kind="improved", params=LOG):
    clock = VirtualClock()
    pubs = []
    fw = make_firmware(
        kind,
        clock,
        lambda topic, v: pubs.append((clock.now_us, topic, v)),
        params,
        edges_per_rev=WHEEL.sc_edges_per_rev,
    )
    fw.start()
    return clock, fw, pubs


def feed_edges(clock, fw, rpm, t_end_us, wheels=(0,), phase_us=137):
    """Synthetic SC edges at a steady ``rpm`` on ``wheels`` until ``t_end_us``."""
    period_us = 60e6 / (90 * rpm)
    k = math.ceil((clock.now_us - phase_us) / period_us) + 1
    while phase_us + k * period_us <= t_end_us:
        t = int(round(phase_us + k * period_us))
        clock.run_until(t - 1)
        clock.set_time(t)
        for w in wheels:
            fw.on_sc_edge(w)
        k += 1
    clock.run_until(t_end_us)


def published(pubs, topic="wheel0_Vel"):
    return [(t, v) for t, topic_, v in pubs if topic_ == topic]


def settling_s(samples, sp, band, t_cmd_us):
    outside = [t for t, v in samples if abs(v - sp) > band]
    return (max(outside) - t_cmd_us) / 1e6 if outside else 0.0


@pytest.mark.parametrize("rpm", [10.0, 76.39, 200.0])
def test_per_edge_speed_within_half_a_percent(rpm):
    """The PI's speed (per SC edge) at every tick, and the published mean above
    extrapolate_above_rpm (at 10 RPM a 100 ms sample holds 1 or 2 whole edges)."""
    clock, fw, pubs = make()
    speeds = []
    for t in range(1_510_000, 3_000_001, 20_000):  # between the PI's ticks
        clock.schedule(t, lambda: speeds.append(fw.speed_rpm[0]))
    feed_edges(clock, fw, rpm, 3_000_000, wheels=(0, 1))
    assert len(speeds) == 75 and max(abs(v / rpm - 1) for v in speeds) < 0.005
    late = [v for t, v in published(pubs) if t > 1_500_000]
    if rpm >= ImprovedParams().extrapolate_above_rpm:
        assert late and max(abs(v / rpm - 1) for v in late) < 0.005
    else:
        assert set(round(v * 0.1 * 90 / 60, 9) for v in late) <= {1.0, 2.0}  # whole edges a sample
        assert np.mean(late) == pytest.approx(rpm, rel=0.05)


def edges_published(pubs, topic="wheel0_Vel"):
    """SC edges the published samples account for: each is the mean since the previous one (100
    ms)."""
    return sum(v * 0.1 * 90 / 60 for _, v in published(pubs, topic))


def test_published_means_count_every_edge():
    """Speeding up, slowing down, stopping, starting again: the samples add up to the edges, so the
    wheel odometry (which takes a sample for the mean since the previous one) counts every edge.
    (tests/experiments/umbmark/test_square.py: what the odometry lost without it.)"""
    clock, fw, pubs = make()
    for rpm, t_end in (
        (5.0, 600_000),
        (30.0, 1_300_000),
        (80.0, 2_100_000),
        (12.0, 2_800_000),
        (3.0, 3_500_000),
    ):
        feed_edges(clock, fw, rpm, t_end, phase_us=clock.now_us + 137)
    clock.run_until(4_500_000)  # stopped: the last edges' sample and zeros
    assert fw._count[0] > 140 and edges_published(pubs) == pytest.approx(fw._count[0], abs=1e-9)
    assert published(pubs)[-1][1] == 0.0 and min(v for _, v in published(pubs)) >= 0.0


def test_zero_speed_timeout_and_fixed_publish_rate():
    clock, fw, pubs = make()
    feed_edges(clock, fw, 60.0, 1_000_000)
    clock.run_until(1_500_000)  # edges stop at 1 s
    samples = published(pubs)
    assert [t for t, _ in samples] == [100_000 * k for k in range(1, 16)]
    assert samples[-1][1] == 0.0 and samples[9][1] == pytest.approx(60.0, rel=0.005)
    # stopped dead from 60 RPM (no wheel can): the part of an edge extrapolated stays counted, less
    # than one
    assert fw.speed_rpm[0] == 0.0 and 0.0 <= edges_published(pubs) - fw._count[0] < 1.0
    assert [v for t, v in samples if 1_000_000 < t] == [
        0.0
    ] * 5  # nothing rolled after the last edge


def test_deceleration_ramps_in_both_directions():
    clock, fw, pubs = make()
    clock.schedule(100_000, lambda: fw.on_wheel_command([1, 150.0, 1, 0]))
    state = simulate(fw, clock, 4_000_000)
    start = len(fw.rt.pin_log)
    fw.on_wheel_command([1, 20.0, 1, 0])
    simulate(fw, clock, 6_000_000, state)
    counts = [c for t, w, c in fw.rt.pin_log[start:] if w == 0 and t < 4_400_000]
    assert counts[0] > 30 and len(set(counts)) > 10  # no jump to the 20 RPM duty (4-5 counts)
    assert np.mean(counts[-5:]) < np.mean(counts[:5])


def test_direction_change_ramps_through_zero_then_flips_dir():
    clock, fw, pubs = make()
    fw.on_wheel_command([1, 60.0, 1, 0])
    state = simulate(fw, clock, 2_000_000)
    fw.on_wheel_command([-1, 60.0, 1, 0])
    simulate(fw, clock, 2_200_000, state)
    assert fw.pins[0].dir_level == HIGH  # still slowing down
    hall, speed, angle = simulate(fw, clock, 4_000_000, state)
    assert fw.pins[0].dir_level == LOW and speed[0] == pytest.approx(-60.0, abs=4)


def test_free_spin_and_brake_semantics():
    clock, fw, pubs = make()
    fw.on_wheel_command([1, 0, -1, 0])
    start = len(fw.rt.pin_log)
    feed_edges(clock, fw, 30.0, 2_000_000, wheels=(0, 1))
    for p in fw.pins:
        assert p.stop_level == LOW and p.brake_level == LOW and p.pwm_counts == 0
    assert len(fw.rt.pin_log) == start  # the PI leaves free-spinning wheels alone
    assert published(pubs)[-1][1] == pytest.approx(30.0, rel=0.005)
    fw.on_wheel_command([0, 0, 0, 0])
    for p in fw.pins:
        assert p.brake_level == HIGH and p.pwm_counts == 0


def test_anti_windup_keeps_the_integral_bounded_when_saturated():
    clock, fw, pubs = make(params=replace(LOG, max_control_rpm=60.0))
    fw.on_wheel_command([1, 100.0, 1, 0])
    feed_edges(clock, fw, 50.0, 5_000_000)  # the wheel cannot follow
    assert fw.integral_rpm[0] <= 60.0 and fw.pins[0].pwm_counts <= int(60 / 1054 * 255) + 1


def test_anti_windup_stops_integrating_where_the_output_saturates():
    """Conditional integration (the condition flipped once survived the suite): inside the
    8 RPM band, after the ramp. Saturated high (max_control 60 RPM, set point 64, the wheel at
    60: error +4), the integral stops once the output reaches 60: at most one tick's ki e dt
    (0.24 RPM) beyond the room left, 60 - 0.9 x 64 - 0.5 x 4 = 0.4 RPM. Saturated low (min_control
    0, set point 10, the wheel at 16: error -6), it stops where the output reaches 0: at -6, and
    one tick (0.36 RPM) at most beyond."""
    clock, fw, pubs = make(params=replace(LOG, max_control_rpm=60.0))
    fw.on_wheel_command([1, 64.0, 1, 0])
    feed_edges(clock, fw, 60.0, 5_000_000)
    assert 0.0 < fw.integral_rpm[0] <= 0.4 + 0.24 + 1e-9
    assert fw.pins[0].pwm_counts in (
        int(60 / 1054 * 255),
        int(60 / 1054 * 255) + 1,
    )  # dithered about 14.5
    clock, fw, pubs = make()
    fw.on_wheel_command([1, 10.0, 1, 0])
    feed_edges(clock, fw, 16.0, 5_000_000)
    assert -6.0 - 0.36 - 1e-9 <= fw.integral_rpm[0] < -5.0


def test_left_wheel_76_rpm_both_modes_settle_and_improved_is_faster():
    sp, band, t_cmd = 76.39, 4.0, 100_000
    result = {}
    for kind in ("faithful", "improved"):
        clock, fw, pubs = make(kind, params=None)
        clock.schedule(t_cmd, lambda fw=fw: fw.on_wheel_command([1, sp, 1, 0]))
        _, speed, _ = simulate(fw, clock, 18_000_000)
        samples = published(pubs)
        late = [v for t, v in samples if t > 4_000_000]
        assert all(abs(v - sp) <= band for v in late)
        result[kind] = (
            settling_s(samples, sp, band, t_cmd),
            settling_s(samples, sp, 1.0, t_cmd),
            late[-1],
            speed[0],
            len(samples),
        )
    for kind, (s4, s1, last, true, n) in result.items():
        print(
            f"\n{kind}: settle +-4 RPM {s4:.2f} s, +-1 RPM {s1:.2f} s, "
            f"last published {last:.2f} RPM, true {true:.2f} RPM, {n} samples"
        )
    assert result["improved"][0] < result["faithful"][0]
    assert abs(result["improved"][3] - sp) < 0.5 < abs(result["faithful"][3] - sp)
