"""Drawn configurations: seeded bytes, Latin hypercube strata, the calibrated parameters drawn
jointly and following the held ones, conditioning on a set value, followers, validity; rank
correlations and intervals; the caster set-up drives the static load split (no mujoco)."""

import json
import subprocess
import sys

import numpy as np
import pytest
import yaml

from amr_twin.model.config import ConfigError
from amr_twin.model.paths import MODEL_DIR
from amr_twin.model.statics import solve
from amr_twin.calibration.draw_statistics import interval, noise_level, rank_correlations
from amr_twin.calibration.uncertainty import ParameterSpace, unit_samples
from amr_twin.model.parameter_spreads import with_values


@pytest.fixture(scope="module")
def space():
    return ParameterSpace.load()


def _draw_json(seed: int) -> str:
    code = (
        "import json; from amr_twin.calibration.uncertainty import ParameterSpace; "
        f"d = ParameterSpace.load().draw(6, seed={seed}); print(json.dumps(d.overrides))"
    )
    return subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True
    ).stdout


def test_same_seed_same_bytes_in_another_process(space):
    here = space.draw(6, seed=7)
    assert _draw_json(7).strip() == json.dumps(here.overrides)
    other = space.draw(6, seed=8)
    assert other.overrides != here.overrides
    assert [here.sample_id(i) for i in range(6)] == [
        space.draw(6, seed=7).sample_id(i) for i in range(6)
    ]


def test_a_setting_no_draw_reads_leaves_the_draws_as_they_are(space):
    """The tyres on and off draw the same robots (chapter 5's paired comparison,
    docs/explanation/tyres.md); a drawn parameter's value set by hand does change them."""
    here = space.draw(8, seed=3)
    rigid = ParameterSpace.load(sets=["wheel.tyre_slip=false"]).draw(8, seed=3)
    assert rigid.names == here.names and np.array_equal(rigid.values, here.values)
    geared = ParameterSpace.load(sets=["driver_left.gain=1.7"]).draw(8, seed=3)
    assert not np.array_equal(geared.values, here.values)


def test_latin_hypercube_puts_one_draw_in_each_stratum(space):
    n = 16
    d = space.draw(n, seed=3, include=("caster.drop_m", "wheel.tyre_stiffness_n_m"))
    for name in d.names:
        s = space.spreads[name]
        strata = np.floor(n * (d.values[:, d.names.index(name)] - s.low) / (s.high - s.low)).astype(
            int
        )
        assert sorted(np.clip(strata, 0, n - 1)) == list(range(n)), name


def test_calibrated_parameters_are_drawn_jointly(space):
    """Gain and Ke keep their 0.99 correlation and the report's sigma: drawn one by one they would
    not."""
    rep = space.calibration
    d = space.draw(
        400, seed=1, include=("driver_left.gain",)
    )  # the whole fit comes along; no held parameter drawn
    assert set(d.names) == set(rep.keys)
    gain, ke = (
        d.values[:, d.names.index("driver_left.gain")],
        d.values[:, d.names.index("motor_left.ke_v_s_rad")],
    )
    assert np.corrcoef(gain, ke)[0, 1] > 0.95
    assert np.std(gain) == pytest.approx(rep.sigma[0], rel=0.15)
    assert np.mean(gain) == pytest.approx(rep.values[0], abs=0.03)
    ratio = gain / ke  # the speed per duty count: pinned far better than either
    assert np.std(ratio) / np.mean(ratio) < 0.5 * np.std(gain) / np.mean(gain)


def test_the_fit_follows_a_drawn_held_parameter(space):
    """Winding resistance is held by the calibration: a drawn resistance moves Ke and the gain
    by the report's d fitted / d held (both motors: the right one follows the left)."""
    rep = space.calibration
    d = space.draw(32, seed=2, include=("motor_left.resistance_ohm",))
    r_left = np.array([o["motor_left.resistance_ohm"] for o in d.overrides])
    r_right = np.array([o["motor_right.resistance_ohm"] for o in d.overrides])
    assert np.allclose(r_right, r_left, rtol=1e-5)  # follows, same nominal 0.3
    j = [
        rep.held_keys.index(k) for k in ("motor_left.resistance_ohm", "motor_right.resistance_ohm")
    ]
    for key in ("driver_left.gain", "motor_left.ke_v_s_rad"):
        slope = rep.follow[rep.keys.index(key), j].sum()
        got = np.array([o[key] for o in d.overrides])
        assert np.allclose(
            got,
            rep.values[rep.keys.index(key)] + slope * (r_left - 0.3),
            atol=2e-5 * abs(got).max(),
        ), key


def test_a_set_calibrated_value_conditions_the_rest():
    free = ParameterSpace.load().draw(200, seed=4, include=("driver_left.gain",))
    fixed = ParameterSpace.load(sets=["driver_left.gain=1.75"]).draw(
        200, seed=4, include=("motor_left.ke_v_s_rad",)
    )
    assert "driver_left.gain" not in fixed.names and all(
        "driver_left.gain" not in o for o in fixed.overrides
    )
    ke_free = free.values[:, free.names.index("motor_left.ke_v_s_rad")]
    ke_fixed = fixed.values[:, fixed.names.index("motor_left.ke_v_s_rad")]
    report = yaml.safe_load((MODEL_DIR / "calibration.yaml").read_text())
    keys = list(report["parameters"])
    r = report["correlation"][keys.index("driver_left.gain")][keys.index("motor_left.ke_v_s_rad")]
    # the conditional spread of a joint normal: sqrt(1 - r^2) of the free one (0.28 at r = 0.96)
    assert np.std(ke_fixed) / np.std(ke_free) == pytest.approx(np.sqrt(1 - r * r), rel=0.2)
    assert (
        np.mean(ke_fixed) > np.mean(ke_free) + 0.01
    )  # a higher gain needs a higher Ke for the same speed


def test_followers_and_vectors(space):
    d = space.draw(16, seed=5)
    for o in d.overrides:
        assert o["wheel.friction"] == pytest.approx(o["sim.floor_friction"], rel=1e-5)
        assert (
            o["components.battery.pos_m"][2] == space.spreads["components.battery.pos_m"].value[2]
        )
    xs = [o["components.battery.pos_m"][0] for o in d.overrides]
    assert np.std(xs) > 0.01


def test_hundreds_of_draws_are_valid_robots(space):
    d = space.draw(512, seed=9)
    assert len(d) == 512 and d.values.shape == (512, len(d.names))
    for i in (0, 100, 511):
        cfg = d.config(space.cfg, i)
        assert cfg.chassis.width_m / 2 < cfg.wheel.separation_m / 2 - cfg.wheel.width_m / 2
    assert set(d.clipped) <= {
        "motor_left.friction_nm",
        "motor_right.friction_nm",
        "motor_left.ke_v_s_rad",
        "motor_right.ke_v_s_rad",
        "driver_left.gain",
        "driver_right.gain",
    }


def test_a_draw_the_schema_refuses_names_its_sample(tmp_path):
    mine = tmp_path / "mine.yaml"
    mine.write_text(
        "chassis:\n  width_m: {value: 0.40, range: [0.38, 0.46], reason: too wide, source: "
        "estimate}\n"
    )
    with pytest.raises(ConfigError, match=r"sample \d+ of seed 0: chassis.width_m: must be <"):
        ParameterSpace.load(override_file=mine).draw(32, seed=0)


def test_samplers():
    assert unit_samples(8, 3, 0, "sobol").shape == (8, 3)
    with pytest.raises(ValueError, match="power of 2"):
        unit_samples(6, 3, 0, "sobol")
    a, b = unit_samples(5, 2, 1), unit_samples(5, 2, 1)
    assert np.array_equal(a, b) and 0 < a.min() and a.max() < 1


def test_rank_correlations_and_intervals():
    rng = np.random.default_rng(0)
    x = rng.uniform(size=(40, 3))
    y = np.exp(3 * x[:, 1]) - x[:, 2]  # monotone in x1, weakly falling in x2
    rho = rank_correlations(x, y)
    assert np.argmax(np.abs(rho)) == 1 and rho[1] > 0.9 and abs(rho[0]) < noise_level(40)
    censored = np.where(x[:, 1] > 0.8, np.inf, y)  # beyond the sweep: ranks last, still counted
    assert rank_correlations(x, censored)[1] > 0.9
    assert np.isnan(rank_correlations(x, np.ones(40))).all()
    i = interval(list(range(101)))
    assert (i["median"], i["low"], i["high"], i["n"]) == (
        50.0,
        pytest.approx(5.0),
        pytest.approx(95.0),
        101,
    )
    d = interval([0, 10, 20, float("inf"), None], discrete=True)
    assert d["n"] == 4 and d["high"] == float("inf") and d["median"] in (10.0, 20.0)
    assert interval([None, float("nan")])["median"] is None


def test_the_caster_set_up_drives_the_static_load_split(space):
    """20 kg at the rear edge: over 48 draws of the whole plant, the front casters' static load is
    moved most by caster.drop_m (the balls' height against the tyres)."""
    from amr_twin.experiments.payload.point import position_xy_m

    d = space.draw(48, seed=11)
    loads = []
    for i in range(len(d)):
        cfg = d.config(space.cfg, i)
        loaded = with_values(
            cfg, {"payload.mass_kg": 20.0, "payload.xy_m": list(position_xy_m(cfg, "rear"))}
        )
        loads.append(solve(loaded).loads_n["caster_front_left"])
    rho = rank_correlations(d.values, loads)
    order = np.argsort(-np.abs(rho))
    assert (
        d.names[order[0]] == "caster.drop_m" and rho[order[0]] > 0.6
    )  # balls lower (drop > 0) take more load
