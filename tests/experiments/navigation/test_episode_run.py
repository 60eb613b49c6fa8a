"""A navigation episode as a worker's item: it travels to a worker process intact, and its row
says the CPU time the episode took."""

import pickle
import time

from amr_twin.experiments.navigation import episode_run
from amr_twin.experiments.navigation.episode_run import EpisodeRun, timed_episode
from amr_twin.experiments.navigation.episodes import Episode


def _item() -> EpisodeRun:
    episode = Episode(3, 7, (1.0, 2.0, 0.5), (9.0, 2.0, -0.5), "clear", None, None)
    return EpisodeRun(None, "aisles", episode, "slam", "map.yaml", controller="dwb")


def test_an_item_pickles_to_an_equal_one():
    item = _item()
    assert pickle.loads(pickle.dumps(item)) == item


def test_the_timed_row_adds_the_cpu_seconds_of_the_episode(monkeypatch):
    def busy(item):
        t0 = time.process_time()
        while time.process_time() - t0 < 0.05:
            pass
        return {"index": item.episode.index, "map": item.map_kind}

    monkeypatch.setattr(episode_run, "run_episode", busy)
    before = time.process_time()
    row = timed_episode(_item())
    assert row["index"] == 3 and row["map"] == "slam"
    assert 0.05 <= row["cpu_s"] <= time.process_time() - before
