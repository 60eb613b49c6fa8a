"""The navigation experiment's typed results write ``metrics.json`` with the keys it always had, in
their order, the static maps left out."""

import json
from dataclasses import fields

from amr_twin.experiments.navigation.result import HallsResult, NavigationResult

MAP_KEYS = [
    "world",
    "episodes",
    "seed",
    "people",
    "maps",
    "localisation",
    "controller",
    "firmware",
    "slam_map",
    "optimal",
    "summary",
    "rows",
    "jobs",
    "wall_s",
    "cpu_s",
]
HALL_KEYS = [
    "worlds",
    "groups",
    "episodes",
    "seed",
    "people",
    "maps",
    "localisation",
    "controller",
    "firmware",
    "optimal",
    "summary",
    "by_world",
    "rows",
    "rows_without_people",
    "jobs",
    "wall_s",
    "cpu_s",
]


def _filled(cls):
    values = {f.name: f"{f.name}-value" for f in fields(cls)}
    values["static_maps"] = {"true": object()}  # not JSON: must stay out of it
    return cls(**values)


def test_metrics_json_keeps_its_keys_in_order_without_the_static_maps():
    for cls, keys in ((NavigationResult, MAP_KEYS), (HallsResult, HALL_KEYS)):
        result = _filled(cls)
        assert list(result.as_json()) == keys
        text = json.dumps(result.as_json(), indent=2)
        assert "static_maps" not in text and '"rows": "rows-value"' in text
        assert result.as_json()["summary"] is result.summary  # the same objects, not copies
