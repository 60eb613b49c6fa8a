"""The sweep's answers over draws, from synthetic rows: crossings interpolated and censored, the
highest safe payload per draw, and the parameter that decides it found by rank correlation (no
simulation)."""

import math

import numpy as np
import pytest

from amr_twin.experiments.payload import spread
from amr_twin.calibration.draws import Draws


def _row(mass, load, sample=None, tilt=0.5, position="rear", command="angular:-60:-1"):
    row = {
        "mass_kg": mass,
        "position": position,
        "command": command,
        "valid": True,
        "error": "",
        "dyn_min_wheel_n": load,
        "max_tilt_deg": tilt,
        "static_tip_margin_m": 0.2,
        "wheel_lift_off": load < 0.5,
        "safe": load >= 0.5 and tilt <= 3.0,
    }
    return row if sample is None else {**row, "sample": sample, "sample_id": f"id{sample}"}


def test_crossing_is_interpolated_and_censored():
    rows = [_row(0, 60.0), _row(20, 20.0), _row(40, -0.0)]
    assert spread.crossing_kg(rows, "dyn_min_wheel_n", 0.5, -1) == pytest.approx(
        20 + 20 * 19.5 / 20.0
    )
    assert (
        spread.crossing_kg([_row(0, 60.0), _row(20, 30.0)], "dyn_min_wheel_n", 0.5, -1) == math.inf
    )
    assert spread.crossing_kg([_row(0, 0.1), _row(20, 30.0)], "dyn_min_wheel_n", 0.5, -1) == 0.0
    tilts = [_row(0, 50, tilt=1.0), _row(20, 50, tilt=2.0), _row(40, 50, tilt=5.0)]
    assert spread.crossing_kg(tilts, "max_tilt_deg", 3.0, +1) == pytest.approx(20 + 20 * 1.0 / 3.0)


def test_answers_and_their_driver():
    """A made-up robot whose wheel load falls faster with payload the higher parameter b is:
    the lift-off mass and the highest safe payload must be found to fall with b, not with a."""
    rng = np.random.default_rng(1)
    n, masses = 24, (0, 10, 20, 30, 40)
    values = rng.uniform(size=(n, 2))
    rows = [_row(m, 60.0 - 1.5 * m) for m in masses]
    for s in range(n):
        slope = 1.0 + 3.0 * values[s, 1]
        rows += [_row(m, 60.0 - slope * m, sample=s) for m in masses]
    draws = Draws(("a", "b"), values, tuple({} for _ in range(n)), 0, "lhs", {})
    results = {"rows": rows, "draws": draws}
    found = spread.answers(results)
    lift = found["rear"]["commands"]["angular:-60:-1"]["lift_off_kg"]
    assert lift["nominal"] == pytest.approx(59.5 / 1.5) and lift["draws"][0] == pytest.approx(
        59.5 / (1.0 + 3.0 * values[0, 1])
    )
    assert lift["low"] <= lift["median"] <= lift["high"] and lift["n"] == n
    assert lift["within"] == int(
        np.sum(59.5 / (1.0 + 3.0 * values[:, 1]) <= 40.0)
    )  # lifts within the swept 40 kg
    safe = found["rear"]["highest_safe_kg"]
    assert safe["nominal"] == 30.0 and set(safe["draws"]) <= set(masses) | {-math.inf}
    sens = spread.sensitivity(results, found)
    top = spread.drivers(sens, "rear", "angular:-60:-1", "lift_off_kg")
    assert top and top[0]["parameter"] == "b" and top[0]["rho"] < -0.9 and top[0]["notable"]
    assert not any(r["notable"] for r in top[1:])  # a is unrelated
    assert [r["parameter"] for r in spread.drivers(sens, "rear", "", "highest_safe_kg")][:1] == [
        "b"
    ]
    never = found["rear"]["commands"]["angular:-60:-1"]["tilt_limit_kg"]
    assert never["nominal"] == math.inf and never["median"] == math.inf


def test_overload_is_judged_by_each_rows_own_rating():
    """The same currents (4, 8, 12 A over 0, 20, 40 kg): with an 11.1 A rating the larger motor
    passes it at 35.5 kg, with a drawn 6 A rating at 10 kg; the smaller motor does not decide."""

    def row(mass, amps, rating):
        return {
            **_row(mass, 50.0),
            "left_steady_current_a": amps,
            "right_steady_current_a": amps / 2,
            "current_limit_a": rating,
        }

    currents = ((0, 4.0), (20, 8.0), (40, 12.0))
    assert spread.crossing_kg(
        [row(m, a, 11.1) for m, a in currents], spread.CURRENT_RATIO, 1.0, +1
    ) == pytest.approx(20 + 20 * 3.1 / 4.0)
    assert spread.crossing_kg(
        [row(m, a, 6.0) for m, a in currents], spread.CURRENT_RATIO, 1.0, +1
    ) == pytest.approx(10.0)
    assert (
        spread.crossing_kg([row(m, a, 13.0) for m, a in currents], spread.CURRENT_RATIO, 1.0, +1)
        == math.inf
    )
    unrated = [
        {k: v for k, v in row(m, a, 11.1).items() if k != "current_limit_a"} for m, a in currents
    ]
    assert math.isnan(
        spread.crossing_kg(unrated, spread.CURRENT_RATIO, 1.0, +1)
    )  # a row of an older sweep
