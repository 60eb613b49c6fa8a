"""The fusion experiment's spec checks its seeds and route from Python, without the CLI."""

import pytest

from amr_twin.experiments.catalogue import experiments
from amr_twin.experiments.fusion.experiment import DEFAULT_ROUTE
from amr_twin.experiments.fusion.spec import FusionSpec
from amr_twin.model.config import load_config


def test_the_default_spec_drives_seed_0_on_the_warehouse_route():
    seeds, route = FusionSpec().validate(load_config())
    assert seeds == [0] and route.name == "warehouse_60m"
    assert FusionSpec(seeds="2:4").seed_list() == [2, 3, 4]
    assert FusionSpec(seed=7).seed_list() == [7]


@pytest.mark.parametrize(
    "spec, named",
    [
        (FusionSpec(seed=1, seeds="0:2"), "--seed and --seeds: give one of them"),
        (FusionSpec(seed=-1), "--seed -1: must be a whole number in [0, 2^32)"),
        (
            FusionSpec(seeds="0:1000000000000"),
            "--seeds '0:1000000000000': 1000000000001 seeds; at most",
        ),
    ],
)
def test_bad_seeds_are_refused_in_one_line_naming_the_field(spec, named):
    with pytest.raises(ValueError) as refused:
        spec.seed_list()
    assert str(refused.value).startswith(named) and "\n" not in str(refused.value)


def test_a_route_unknown_or_outside_its_world_is_refused_naming_it(tmp_path):
    unknown = r"^--route nowhere: no such route file, nor a route of the twin \(.*corridor"
    with pytest.raises(ValueError, match=unknown):
        FusionSpec(route="nowhere").load_route()
    outside = tmp_path / "outside.yaml"
    outside.write_text(DEFAULT_ROUTE.read_text().replace("  - [6.2, -1.4]\n", "  - [60.0, -1.4]\n"))
    spec = FusionSpec(route=str(outside))
    with pytest.raises(ValueError) as refused:
        spec.validate(load_config())
    assert str(refused.value).startswith(f"--route {outside}: ")
    assert "lies outside the world" in str(refused.value)


def test_the_registry_holds_fusion_with_its_spec():
    assert experiments().get("fusion").spec is FusionSpec
