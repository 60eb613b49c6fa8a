"""The brush tyres' explicit states, converged in the timestep at the stiff corner of their ranges.

The tyre's deflection and its rubber damping are advanced explicitly (amr_twin/sim/tyres.py), so
the carcass is stable only while ``(k_x dt + tau k_x) dt / (J / r^2)`` stays below about 2
(docs/explanation/tyres.md, "Not found: convergence to the rigid contact"). Chapter 5's 20 kg turn
(run 8) with every tyre parameter at the stiff end of its sourced range (slip stiffness 25,
cornering 17 /rad, relaxation lengths 0.02 and 0.04 m, loss time 10 ms): at 1 ms and at 0.5 ms the
true wheel speeds agree within 0.5 RPM from 4.5 s on (the ramp's and the PI's events fall on other
steps before), and their final values within 0.1 RPM. (With the tyres' guard,
amr_twin/model/tyre_stability.py, the 1 ms configuration runs at 0.5 ms: S = 2.15 at 1.3 times the
static 126 N; the 0.5 ms one stays: S = 1.03.)

With 50 kg the stiff longitudinal corner (slip stiffness 25, relaxation 0.02 m, loss time 10 ms)
is unstable at 1 ms (run 3 ended at 85 RPM instead of 52): the guard halves the timestep twice
(S = 3.70 -> 0.86), and run 3 at the configured 1 ms ends where the same draw configured at
0.25 ms (which the guard leaves) does, within 0.05 RPM, on the same 10 ms record grid.
"""

import dataclasses

import numpy as np
import pytest

from amr_twin.experiments.chapter5 import runs as chapter5
from amr_twin.model.config import load_config

STIFF = [
    "wheel.slip_stiffness_per_n=25",
    "wheel.relaxation_length_longitudinal_m=0.02",
    "wheel.cornering_stiffness_per_n=17",
    "wheel.relaxation_length_lateral_m=0.04",
    "wheel.tyre_loss_time_s=0.01",
]


def _true_rpm(timestep_s: float):
    cfg = load_config(sets=STIFF + [f"sim.timestep_s={timestep_s}"])
    spec = chapter5.RUNS[7]
    assert spec.payload_kg == 20.0
    raw = chapter5.simulate(chapter5.RunJob(spec, cfg, "faithful", 6.0))
    return np.asarray(raw["t_s"]), np.asarray(raw["true_rpm"])


@pytest.fixture(scope="module")
def runs():
    return _true_rpm(0.001), _true_rpm(0.0005)


def test_stiff_tyres_converge_in_the_timestep(runs):
    (t1, y1), (t2, y2) = runs
    assert np.max(np.abs(y1[:, 0])) > 90.0  # the outer wheel drove up to its 99 RPM
    keep = t1 > 4.5
    for w in range(2):
        fine = np.interp(t1[keep], t2, y2[:, w])
        assert np.max(np.abs(y1[keep, w] - fine)) < 0.5
        assert abs(np.mean(y1[-50:, w]) - np.mean(y2[t2 >= t1[-50], w])) < 0.1


LONGITUDINAL = [
    "wheel.slip_stiffness_per_n=25",
    "wheel.relaxation_length_longitudinal_m=0.02",
    "wheel.tyre_loss_time_s=0.01",
]


def _run3_50kg(timestep_s: float):
    cfg = load_config(sets=LONGITUDINAL + [f"sim.timestep_s={timestep_s}"])
    spec = dataclasses.replace(chapter5.RUNS[2], payload_kg=50.0)
    return chapter5.simulate(chapter5.RunJob(spec, cfg, "faithful", spec.duration_s))


def test_guard_makes_the_unstable_corner_run_right_at_1ms():
    coarse, fine = _run3_50kg(0.001), _run3_50kg(0.00025)
    assert fine["tyre_timestep"] is None  # 0.25 ms is stable: the reference runs as configured
    assert (
        coarse["tyre_timestep"]["timestep_s"] == 0.00025
        and coarse["tyre_timestep"]["halvings"] == 2
    )
    t, y = np.asarray(coarse["t_s"]), np.asarray(coarse["true_rpm"])
    assert len(t) == 1601 and t[1] == pytest.approx(
        0.01
    )  # the 10 ms grid kept (the reference's is 2.5 ms)
    np.testing.assert_allclose(t, np.asarray(fine["t_s"])[::4], atol=1e-9)
    last = t >= 15.0
    final = np.mean(y[last], axis=0)
    reference = np.mean(np.asarray(fine["true_rpm"])[::4][last], axis=0)
    assert np.all(np.abs(final - reference) < 0.05)
    assert np.all(
        (final > 50.0) & (final < 55.0)
    )  # run 3's 53.5 RPM reference; unguarded it ended at 85
    assert np.max(np.abs(y)) < 60.0
