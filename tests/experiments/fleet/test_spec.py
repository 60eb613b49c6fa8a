"""The fleet spec refuses bad input in one line naming the field, before any episode; it is
registered beside the other experiments."""

import pytest

from amr_twin.experiments.catalogue import experiments
from amr_twin.experiments.fleet.spec import FleetSpec


@pytest.mark.parametrize(
    "kwargs, message",
    [
        (dict(robots=(0,)), r"^--robots 0: distinct whole numbers in \[1, 20\]$"),
        (dict(robots=(1, 21)), r"^--robots 1,21: "),
        (dict(robots=(1, 1)), r"^--robots 1,1: "),
        (dict(payload_kg=((0.0, 60.0),)), r"^--payload-kg 0-60: .*\(50 kg\)$"),
        (dict(payload_kg=((-1.0, 10.0),)), r"^--payload-kg -1-10: "),
        (dict(payload_kg=((20.0, 10.0),)), r"^--payload-kg 20-10: "),
        (dict(payload_kg=()), r"^--payload-kg nan-nan: "),
        (dict(seeds=()), r"^--seeds : "),
        (dict(seeds=(-1,)), r"^--seeds -1: "),
        (dict(duration_s=0.0), r"^--duration-s 0: "),
        (dict(duration_s=float("inf")), r"^--duration-s inf: "),
        (dict(jobs_per_hour=0.0), r"^--jobs-per-hour 0: "),
        (dict(near_miss_m=0.0), r"^--near-miss-m 0: "),
        (dict(charge_below=80.0), r"^--charge-below 80: "),
        (dict(world="no_such_world"), r"^--world no_such_world: "),
    ],
)
def test_bad_input_is_one_line_naming_the_field(kwargs, message):
    spec = FleetSpec(**{"robots": (1,), **kwargs})
    with pytest.raises(ValueError, match=message):
        spec.validate(50.0)


def test_fleets_of_1_to_20_robots_are_accepted():
    points = FleetSpec(tuple(range(1, 21)), seeds=(0,)).validate(50.0)
    assert [p.robots for p in points] == list(range(1, 21))


def test_the_episodes_run_by_mix_fleet_size_and_seed():
    points = FleetSpec((1,), ((0.0, 10.0), (20.0, 30.0)), (2, 0), 60.0).validate(50.0)
    assert [(p.payload_kg, p.robots, p.seed) for p in points] == [
        ((0.0, 10.0), 1, 2),
        ((0.0, 10.0), 1, 0),
        ((20.0, 30.0), 1, 2),
        ((20.0, 30.0), 1, 0),
    ]
    assert {p.duration_s for p in points} == {60.0}


def test_the_fleet_experiment_is_registered():
    entry = experiments().get("fleet")
    assert entry.spec is FleetSpec and "orders per hour" in entry.about
