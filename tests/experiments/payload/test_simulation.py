"""One payload sweep point simulated: an off-deck position is invalid, an overloaded motor
unsafe."""

import pytest

from amr_twin.model.config import load_config
from amr_twin.experiments.payload.limits import unsafe_reason
from amr_twin.experiments.payload.point import Point
from amr_twin.experiments.payload.simulation import simulate_point

DURATION_S = 2.0


@pytest.fixture(scope="module")
def cfg():
    return load_config()


def test_off_deck_position_is_invalid(cfg):
    row = simulate_point(Point(10.0, "0.5:0", "linear:0.7", DURATION_S, "faithful", cfg)).as_json()
    assert row["valid"] is False and row["safe"] is False and "outside the deck" in row["error"]
    assert unsafe_reason(row).startswith("invalid payload: payload.xy_m")


def test_a_motor_over_the_drivers_continuous_rating_is_unsafe():
    """The same point, once with the shipped rating (11.1 A) and once with a rating the
    motors exceed while driving (0.6 A): only the second is unsafe, with the reason."""
    low = load_config(sets=["driver.continuous_current_a=0.6"])
    ok = simulate_point(
        Point(0.0, "center", "linear:0.7", DURATION_S, "faithful", load_config())
    ).as_json()
    over = simulate_point(Point(0.0, "center", "linear:0.7", DURATION_S, "faithful", low)).as_json()
    assert ok["safe"] and not ok["motor_overload"]
    assert 0.6 < max(over["left_steady_current_a"], over["right_steady_current_a"]) < 11.1
    assert not over["safe"] and over["motor_overload"]
    assert unsafe_reason(over).startswith(
        "motor current rating (wheels tracking)"
    )  # not a runaway: it tracks
