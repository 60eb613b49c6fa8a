"""An episode recorded (``amr-twin experiment fleet --record``): one .mcap and one .rrd holding
every robot, and the episode's measures the same as unrecorded."""

import collections
import json

from amr_twin.experiments.fleet.episode import run_episode
from amr_twin.experiments.fleet.result import EpisodePoint
from amr_twin.model.config import load_config

POINT = EpisodePoint(2, (0.0, 30.0), 0, 20.0, 300.0)


def _bytes(result) -> str:
    data = result.as_json()
    data.pop("wall_s"), data.pop("cpu_s")
    return json.dumps(data, sort_keys=True)


def test_a_recorded_episode_holds_every_robot_and_measures_the_same(tmp_path):
    from mcap.reader import make_reader

    cfg = load_config()
    recorded = run_episode(cfg, POINT, tmp_path)
    assert _bytes(recorded) == _bytes(run_episode(cfg, POINT))
    stem = tmp_path / "fleet_2r_0-30kg_s0"
    counts = collections.Counter()
    with open(stem.with_suffix(".mcap"), "rb") as f:
        for _schema, channel, _message in make_reader(f).iter_messages():
            counts[channel.topic] += 1
    truth = [counts[f"/amr-{i}/twin/ground_truth"] for i in (1, 2)]
    assert truth[0] == truth[1] == counts["/clock"] > 0
    assert counts["/amr-1/scan"] > 0 and counts["/amr-2/scan"] > 0
    assert stem.with_suffix(".rrd").stat().st_size > 10_000
