"""`amr-twin experiment navigation` on a ROS map world: the generated warehouse runs from the
command line."""

import json

from amr_twin.cli.main import app

from nav_grids import random_warehouse, write_map


def _call(args) -> int:
    try:
        app([str(a) for a in args])
    except SystemExit as exc:
        return int(exc.code or 0)
    return 0


def test_a_ros_map_world_runs_on_its_true_map_and_asks_for_a_slam_map(tmp_path, capsys):
    """A map the code has never seen (generated here), given as --world: one episode on its true
    map, written as for an MJCF world; asking for the SLAM map too, without --slam-map, is refused
    in one line before any episode (no mapping drive to build it from)."""
    world = write_map(tmp_path, "unseen", random_warehouse(31))
    assert (
        _call(
            [
                "experiment",
                "navigation",
                "--world",
                world,
                "--episodes",
                1,
                "--out",
                tmp_path / "a",
                "--no-progress",
            ]
        )
        == 2
    )
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--world" in err[0] and "--maps true or --slam-map" in err[0], err
    assert not (tmp_path / "a").exists()
    assert (
        _call(
            [
                "experiment",
                "navigation",
                "--world",
                world,
                "--maps",
                "true",
                "--episodes",
                1,
                "--jobs",
                1,
                "--out",
                tmp_path / "b",
                "--no-progress",
            ]
        )
        == 0
    )
    data = json.loads((tmp_path / "b" / "metrics.json").read_text())
    assert [r["map"] for r in data["rows"]] == ["true"] and data["rows"][0]["success"], data["rows"]
    assert (tmp_path / "b" / "trajectories_true.png").stat().st_size > 10_000
