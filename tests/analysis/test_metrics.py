"""step_info on analytic signals (no simulation)."""

import math

import numpy as np
import pytest

from amr_twin.analysis.metrics import step_info

T = np.linspace(0.0, 10.0, 100_001)  # 0.1 ms: interpolation error far below the tolerances


def first_order(t, k=50.0, tau=0.4):
    return k * (1.0 - np.exp(-t / tau))


def second_order(t, zeta=0.3, wn=6.0):
    wd = wn * math.sqrt(1 - zeta**2)
    phi = math.acos(zeta)
    return 1.0 - np.exp(-zeta * wn * t) / math.sqrt(1 - zeta**2) * np.sin(wd * t + phi)


def test_first_order_times():
    tau = 0.4
    info = step_info(T, first_order(T, tau=tau), 50.0)
    assert info.delay_s == pytest.approx(tau * math.log(2), abs=1e-3)
    assert info.rise_s == pytest.approx(tau * math.log(9), abs=1e-3)
    assert info.overshoot == 0.0 and info.overshoot_pct == 0.0
    assert info.settling_band == pytest.approx(2.5)  # 5 % of the step by default
    assert info.settling_s == pytest.approx(tau * math.log(20), abs=1e-3)
    assert info.steady_error == pytest.approx(0.0, abs=1e-6)
    assert info.oscillation == pytest.approx(0.0, abs=1e-9)


def test_second_order_overshoot_and_peak():
    zeta, wn = 0.3, 6.0
    y = 80.0 * second_order(T, zeta, wn)
    info = step_info(T, y, 80.0, settling_band=0.02 * 80.0)
    expected_pct = 100 * math.exp(-zeta * math.pi / math.sqrt(1 - zeta**2))
    assert info.overshoot_pct == pytest.approx(expected_pct, abs=1e-3)
    assert info.overshoot == pytest.approx(0.8 * expected_pct, abs=1e-3)
    assert info.peak_s == pytest.approx(math.pi / (wn * math.sqrt(1 - zeta**2)), abs=1e-3)
    assert info.peak_value == pytest.approx(80.0 + info.overshoot)
    # settling: last time |y - 80| > 1.6, found by brute force on the dense signal
    last_out = T[np.nonzero(np.abs(y - 80.0) > 1.6)[0][-1]]
    assert info.settling_s == pytest.approx(last_out, abs=1e-3)
    assert info.oscillation > 2 * info.overshoot  # up and down at least once


def test_oscillation_grows_as_damping_falls():
    lightly = step_info(T, second_order(T, 0.15), 1.0).oscillation
    damped = step_info(T, second_order(T, 0.5), 1.0).oscillation
    assert lightly > damped > 0.0


def test_sign_normalised_and_t0():
    t0 = 2.0
    y = np.where(T < t0, 0.0, -first_order(T - t0, k=91.67))
    info = step_info(T, y, -91.67, t0_s=t0)
    assert info.reference == 91.67
    assert info.delay_s == pytest.approx(0.4 * math.log(2), abs=1e-3)
    assert info.final_value > 0


def test_sparse_samples_interpolate_from_rest():
    # samples at 1, 2, 3 s of a signal that is at rest at t0 = 0: linear interpolation
    t = np.array([1.0, 2.0, 3.0, 4.0])
    y = np.array([40.0, 52.0, 50.0, 50.0])
    info = step_info(t, y, 50.0, settling_band=1.0)
    assert info.delay_s == pytest.approx(25.0 / 40.0)  # 0 -> 40 between 0 and 1 s
    assert info.rise_s == pytest.approx((1.0 + 5.0 / 12.0) - 5.0 / 40.0)  # 45 between 1 and 2 s
    assert info.peak_s == 2.0 and info.overshoot == pytest.approx(2.0)
    # leaves the band at 2 s (52), back in at 51 between 2 and 3 s
    assert info.settling_s == pytest.approx(2.5)
    # window from t90 = 1.417 s (45): up 52 - 45, down 2: excess variation = 9 - 5 = 4
    assert info.oscillation == pytest.approx(4.0)


def test_a_response_that_ends_short_is_timed_on_its_final_value_and_its_offset_said():
    """Ogata's times are fractions of the final value; the shortfall is the steady error's."""
    t = np.linspace(0, 5, 51)
    info = step_info(t, 0.3 * np.minimum(t, 1.0), 1.0)
    assert info.final_value == pytest.approx(0.3) and info.steady_error == pytest.approx(-0.7)
    assert info.delay_s == pytest.approx(0.5) and info.rise_s == pytest.approx(0.8)
    assert info.overshoot == 0.0 and math.isnan(info.peak_s)  # a ramp and a plateau: no peak
    at_rest = step_info(t, np.zeros_like(t), 1.0)
    assert math.isnan(at_rest.delay_s) and math.isnan(at_rest.rise_s)
    assert at_rest.as_dict()["delay_s"] is None and at_rest.steady_error == -1.0


def test_a_permanent_offset_is_a_steady_error_not_an_overshoot():
    """Chapter 5 run 6, right wheel: a monotone rise to 105.17 RPM against 99.20."""
    y = first_order(T, k=105.17, tau=0.5)
    info = step_info(T, y, 99.20, settling_band=4.96)
    assert info.overshoot == 0.0 and info.overshoot_pct == 0.0
    assert (
        math.isnan(info.peak_s) and math.isnan(info.peak_value) and info.as_dict()["peak_s"] is None
    )
    assert info.steady_error == pytest.approx(5.97, abs=1e-3)
    # settled about its own final value: 4.96 RPM is 4.72 % of the step, exp(-t/tau) = 0.0472
    assert info.settling_s == pytest.approx(-0.5 * math.log(4.96 / 105.17), abs=1e-3)
    # sampled once per revolution as the firmware publishes it, the same
    ts = np.arange(1.56, 16.0, 0.8)
    sparse = step_info(ts, first_order(ts, k=105.17, tau=0.5), 99.20)
    assert sparse.overshoot == 0.0 and math.isnan(sparse.peak_s)


def test_overshoot_is_measured_from_the_final_value_it_comes_back_to():
    """Run 4's shape: up to 99.17, back to 93.98 (reference 91.67): 5.19 over, 2.31 off."""
    t = np.array([1.15, 2.01, 3.01, 4.01, 5.01, 6.03, 7.04, 8.04, 12.0, 15.0])
    y = np.array([63.64, 99.02, 99.17, 99.14, 99.10, 95.31, 94.06, 93.98, 93.98, 93.98])
    info = step_info(t, y, 91.67)
    assert info.peak_s == 3.01 and info.peak_value == 99.17
    assert info.overshoot == pytest.approx(99.17 - 93.98)
    assert info.overshoot_pct == pytest.approx(100 * (99.17 - 93.98) / 93.98)
    assert info.steady_error == pytest.approx(93.98 - 91.67)


def test_no_peak_while_still_rising_or_within_the_tolerance():
    t = np.arange(1.0, 11.0)
    rising = step_info(t, 10.0 * t, 100.0)  # its maximum is its last sample
    assert rising.overshoot == 0.0 and math.isnan(rising.peak_s)
    wobble = 10.0 * t
    wobble[-1] = wobble[-2] - 0.05  # still rising but for 0.05 at the end: it does not come back
    assert step_info(t, wobble, 100.0).overshoot == 0.0
    flat = np.array([40.0, 99.0, 100.00005, 100.0, 100.0, 100.0, 100.0, 100.0, 100.0, 100.0])
    assert math.isnan(step_info(t, flat, 100.0).peak_s)  # 5e-5 over: below 0.1 % of the step
    bump = flat.copy()
    bump[2] = 100.5
    info = step_info(t, bump, 100.0)
    assert info.peak_s == 3.0 and info.overshoot == pytest.approx(0.5)


def test_steady_error_from_the_tail():
    y = first_order(T, k=48.0)
    info = step_info(T, y, 50.0, settling_band=4.0)
    assert info.steady_error == pytest.approx(-2.0, abs=1e-3)
    assert math.isfinite(info.settling_s)


def test_bad_input():
    with pytest.raises(ValueError):
        step_info([0, 1], [0, 1], 0.0)
    with pytest.raises(ValueError):
        step_info([0, 1, 2], [0, 1], 1.0)


def test_peak_time_is_the_first_peak_of_a_rippled_plateau():
    """Ogata's t_p (first peak) and M_p (maximum peak): on run 4's shape, a plateau whose ripples
    differ by 0.1-0.7 RPM (far above the 0.1 % tolerance), the peak time is the first ripple, the
    overshoot the highest one; a ripple inside the tolerance is not a peak of its own."""
    t = np.round(np.arange(0.0, 12.0, 0.01), 2)
    y = np.where(t < 1.0, 99.0 * t, 99.0) + np.where(t < 6.0, 0.0, -4.0 * np.minimum(t - 6.0, 1.0))
    y = y + 0.4 * np.exp(-(((t - 1.2) / 0.05) ** 2)) + 1.1 * np.exp(-(((t - 4.2) / 0.05) ** 2))
    info = step_info(t, y, 95.0)
    assert info.peak_s == pytest.approx(1.2)
    assert info.peak_value == pytest.approx(100.1, abs=1e-6)
    assert info.overshoot == pytest.approx(5.1, abs=1e-6)
    # the first ripple shrunk to 0.05 RPM, below the tolerance (0.095 RPM): the first peak is the
    # later one
    low = np.where(t < 1.0, 99.0 * t, 99.0) + np.where(
        t < 6.0, 0.0, -4.0 * np.minimum(t - 6.0, 1.0)
    )
    low = low + 0.05 * np.exp(-(((t - 1.2) / 0.05) ** 2)) + 1.1 * np.exp(-(((t - 4.2) / 0.05) ** 2))
    assert step_info(t, low, 95.0).peak_s == pytest.approx(4.2)
    # a first ripple that does not come back down by the tolerance before rising further is no peak
    stair = np.where(t < 1.0, 99.0 * t, 99.0 + 0.2 * np.minimum(np.maximum(t - 1.2, 0.0), 3.0))
    stair = stair + np.where(t < 6.0, 0.0, -4.6 * np.minimum(t - 6.0, 1.0))
    assert step_info(t, stair, 95.0).peak_s == pytest.approx(4.2)
