"""Payload sweep points: the named positions lie on the deck; the --masses and --commands
parsers."""

import pytest

from amr_twin.model.config import load_config
from amr_twin.experiments.payload import point as pp


@pytest.fixture(scope="module")
def cfg():
    return load_config()


def test_named_positions_lie_on_the_deck(cfg):
    for name in pp.POSITIONS:
        x, y = pp.position_xy_m(cfg, name)
        pp.with_payload(cfg, 20.0, (x, y))  # raises ConfigError if off the deck
    assert pp.position_xy_m(cfg, "front-left-corner") == (pytest.approx(0.2), pytest.approx(0.075))


def test_parsing():
    assert pp.parse_masses("0:60:20") == [0, 20, 40, 60]
    assert pp.parse_masses("5,10") == [5, 10]
    for bad in ("0:60:0", "a", "-5", "nan"):
        with pytest.raises(ValueError):
            pp.parse_masses(bad)
    assert pp.parse_command("angular:60:-1").icc_m == -1.0
    assert pp.parse_command("motor:right:-1").direction == "backward"
    with pytest.raises(ValueError):
        pp.parse_command("spin:3")


def test_a_points_fingerprint_covers_what_its_result_depends_on(cfg):
    """A resumed sweep reuses a point's file only when its fingerprint matches (one that
    ignored the duration would have reused a point simulated for another duration)."""
    base = pp.Point(20.0, "rear", "linear:0.7", 8.0, "faithful", cfg)
    same = pp.Point(
        20.0, "rear", "linear:0.7", 8.0, "faithful", cfg, rrd_path="x.rrd", mcap_path="x.mcap"
    )
    assert same.fingerprint == base.fingerprint  # where it is recorded does not change it
    others = [
        pp.Point(20.0, "rear", "linear:0.7", 4.0, "faithful", cfg),
        pp.Point(20.0, "rear", "linear:0.7", 8.0, "improved", cfg),
        pp.Point(
            20.0, "rear", "linear:0.7", 8.0, "faithful", pp.with_payload(cfg, 1.0, (0.0, 0.0))
        ),
    ]
    assert len({base.fingerprint, *(o.fingerprint for o in others)}) == 4
