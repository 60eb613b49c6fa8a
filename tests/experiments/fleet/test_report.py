"""The fleet report on made-up episodes of 1, 2, 4 and 8 robots: medians per fleet size, where
throughput saturates, energy by payload bin, the plots."""

import json

from amr_twin.experiments.fleet.report import FleetResult, markdown, write
from amr_twin.experiments.fleet.result import EpisodePoint, EpisodeResult, JobRecord, RobotRecord
from amr_twin.model.config import load_config

THROUGHPUT = {
    1: (50.0, 54.0, 52.0),
    2: (100.0, 96.0, 104.0),
    4: (180.0, 190.0, 185.0),
    8: (195.0, 200.0, 190.0),
}  # 4 -> 8 robots: + 5 %


def _episode(n: int, seed: int) -> EpisodeResult:
    robots = [
        RobotRecord(
            f"amr-{i + 1}", 300.0, 0.5, 0.0, 5.0, [], [[0.0, -6.0 + i, 0.0], [0.5, -5.0 + i, 0.5]]
        )
        for i in range(n)
    ]
    jobs = [
        JobRecord(
            f"job-{k}",
            kg,
            10.0 * k,
            "amr-1",
            10.0 * k,
            10.0 * k + 60,
            False,
            0.5 + kg / 100,
            40.0,
            30.0,
            0.1 + kg / 100,
        )
        for k, kg in enumerate((2.0, 12.0, 25.0))
    ]
    return EpisodeResult(
        EpisodePoint(n, (0.0, 30.0), seed, 600.0, 300.0),
        jobs,
        robots,
        THROUGHPUT[n][seed],
        60.0,
        90.0,
        0.62,
        0,
        0,
        [],
        3.0 if n > 1 else None,
    )


def _result():
    return FleetResult([_episode(n, s) for n in (1, 2, 4, 8) for s in range(3)])


def test_the_report_says_where_throughput_saturates_and_tables_each_fleet_size():
    summary = _result().summary()[0]
    assert summary["saturates_at_robots"] == 4
    assert [r["orders_per_hour_median"] for r in summary["by_fleet_size"]] == [
        52.0,
        100.0,
        185.0,
        195.0,
    ]
    text = markdown(_result().as_json())
    assert "throughput saturates at 4 robots" in text
    assert "| 8 | 195.0 (195.0, 200.0, 190.0) |" in text
    bins = summary["energy_by_payload"]
    assert [b["orders"] for b in bins] == [12, 12, 12]
    assert [round(b["energy_wh_median"], 2) for b in bins] == [0.52, 0.62, 0.75]
    assert summary["driving_energy_fit"]["wh_per_km_per_10kg"] == 3.333  # 0.1 Wh per 30 m, 10 kg
    assert "+3.33 Wh/km per 10 kg of payload" in text


def test_write_puts_the_json_the_markdown_and_a_plot_per_fleet_size(tmp_path):
    write(_result(), load_config(), tmp_path)
    data = json.loads((tmp_path / "metrics.json").read_text())
    assert len(data["episodes"]) == 12 and data["summary"][0]["saturates_at_robots"] == 4
    names = sorted(p.name for p in tmp_path.iterdir())
    assert names == [
        "metrics.json",
        "report.md",
        "throughput.png",
        "tracks_1.png",
        "tracks_2.png",
        "tracks_4.png",
        "tracks_8.png",
    ]
    assert all((tmp_path / n).stat().st_size > 5000 for n in names if n.endswith(".png"))
