"""The brush tyres' explicit states, converged in the timestep at the stiff corner of their ranges.

The tyre's deflection and its rubber damping are advanced explicitly (amr_twin/sim/tyres.py), so
the carcass is stable only while ``(k_x dt + tau k_x) dt / (J / r^2)`` stays below about 2
(docs/tyres.md, "Not found: convergence to the rigid contact"). Chapter 5's 20 kg turn (run 8)
with every tyre parameter at the stiff end of its sourced range (slip stiffness 25, cornering 17
/rad, relaxation lengths 0.02 and 0.04 m, loss time 10 ms): at 1 ms and at 0.5 ms the true wheel
speeds agree within 0.5 RPM from 4.5 s on (the ramp's and the PI's events fall on other steps before), and their final values within 0.1 RPM.
"""

import numpy as np
import pytest

from amr_twin.experiments import chapter5
from amr_twin.model.config import load_config

STIFF = ["wheel.slip_stiffness_per_n=25", "wheel.relaxation_length_longitudinal_m=0.02",
         "wheel.cornering_stiffness_per_n=17", "wheel.relaxation_length_lateral_m=0.04",
         "wheel.tyre_loss_time_s=0.01"]


def _true_rpm(timestep_s: float):
    cfg = load_config(sets=STIFF + [f"sim.timestep_s={timestep_s}"])
    spec = chapter5.RUNS[7]
    assert spec.payload_kg == 20.0
    raw = chapter5.simulate(chapter5._Job(spec, cfg, "faithful", 6.0))
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
