"""The tyres' timestep guard (amr_twin/model/tyre_stability.py): S from the configuration, the
halving.

Expectations by hand (docs/explanation/tyres.md): J / r^2 = 0.5 x 2.1 kg x 0.125^2 / 0.125^2 = 1.05
kg; nominal tyre at its static 65.6 N: k_x = 15 x 65.6 / 0.04 = 24 600 N/m,
S = (24.6 + 123) 1e-3 / 1.05 = 0.141. Stiff longitudinal corner (slip stiffness 25, relaxation
0.02 m, loss 10 ms) with 50 kg (static wheel load 217.4 N, x 1.3): k_x = 353 275 N/m,
S(1 ms) = (353.3 + 3532.8) 1e-3 / 1.05 = 3.70, S(0.5 ms) = 1.77, S(0.25 ms) = 0.86.
"""

import numpy as np
import pytest

from amr_twin.model.config import load_config
from amr_twin.model.tyre_stability import (
    TyreTimestepError,
    rotating_mass_kg,
    stability_number,
    tyre_timestep,
)

STIFF = [
    "wheel.slip_stiffness_per_n=25",
    "wheel.relaxation_length_longitudinal_m=0.02",
    "wheel.tyre_loss_time_s=0.01",
]


def test_nominal_tyre_keeps_the_timestep():
    cfg = load_config()
    assert rotating_mass_kg(cfg) == pytest.approx(1.05, rel=1e-3)
    assert stability_number(24_600.0, 0.005, 0.001, 1.05) == pytest.approx(0.141, abs=1e-3)
    step = tyre_timestep(cfg)
    assert step.load_n[0] == pytest.approx(65.6, abs=0.2)
    assert max(step.s_configured) == pytest.approx(0.141 * 1.3, abs=2e-3)
    assert (step.halvings, step.timestep_s) == (0, 0.001)


def test_stiff_corner_at_50kg_is_halved_twice():
    step = tyre_timestep(load_config(sets=STIFF + ["payload.mass_kg=50"]))
    assert step.load_n[0] == pytest.approx(217.4, abs=0.2)
    assert max(step.s_configured) == pytest.approx(3.70, abs=0.01)
    assert step.halvings == 2 and step.timestep_s == 0.00025 and step.steps_per_configured_step == 4
    assert max(step.s) == pytest.approx(0.86, abs=0.01)
    assert step.as_dict()["timestep_s"] == 0.00025


def test_stiff_corner_at_20kg_is_halved_once_and_an_explicit_fine_step_is_kept():
    assert tyre_timestep(load_config(sets=STIFF + ["payload.mass_kg=20"])).timestep_s == 0.0005
    assert (
        tyre_timestep(
            load_config(sets=STIFF + ["payload.mass_kg=50", "sim.timestep_s=0.00025"])
        ).halvings
        == 0
    )


def test_rigid_contact_is_not_guarded():
    step = tyre_timestep(load_config(sets=STIFF + ["payload.mass_kg=50", "wheel.tyre_slip=false"]))
    assert step.halvings == 0


def test_a_timestep_halving_cannot_keep_on_whole_microseconds_is_refused():
    with pytest.raises(
        TyreTimestepError, match=r"sim.timestep_s: 0.00125 .*slip_stiffness_per_n 25.*S = 4.7"
    ):
        tyre_timestep(load_config(sets=STIFF + ["payload.mass_kg=50", "sim.timestep_s=0.00125"]))


@pytest.mark.parametrize("tau_s", [0.002, 0.005, 0.01])
def test_the_linearised_update_is_stable_below_two_plus_a_half(tau_s):
    """The boundary the module's docstring derives (S < 2 + a/2, a = k dt^2 / M), found from the
    eigenvalues of one step of the update (deflection u, slip velocity s) as the stiffness grows."""
    dt, m = 0.001, 1.05
    stiffness = np.geomspace(1e3, 1e6, 3000)
    radius = []
    for k in stiffness:
        a, b = k * dt * dt / m, tau_s * k * dt / m
        radius.append(
            np.max(np.abs(np.linalg.eigvals(np.array([[1.0, -dt], [dt * k / m, 1.0 - (a + b)]]))))
        )
    k = stiffness[np.argmax(np.array(radius) > 1.0 + 1e-9)]
    assert stability_number(k, tau_s, dt, m) == pytest.approx(2.0 + k * dt * dt / m / 2.0, rel=5e-3)


def test_a_halving_is_said_on_stderr_once(monkeypatch, capsys):
    from amr_twin.model import tyre_stability

    monkeypatch.setattr(tyre_stability, "_announced", set())
    tyre_stability.announce(tyre_timestep(load_config()))
    assert capsys.readouterr().err == ""
    halved = tyre_timestep(load_config(sets=STIFF + ["payload.mass_kg=50"]))
    tyre_stability.announce(halved)
    tyre_stability.announce(halved)
    err = capsys.readouterr().err.splitlines()
    assert len(err) == 1 and "halved to 0.25 ms" in err[0] and "S = 3.70 > 1.5" in err[0]
