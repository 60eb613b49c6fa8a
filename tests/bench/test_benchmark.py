"""amr-twin bench: the figures the README quotes are all there and consistent (not timed)."""

import statistics

import pytest

from amr_twin.bench.figures import run_benchmarks
from amr_twin.model.config import load_config

FIGURES = (
    "loop",
    "sensors",
    "actors",
    "actors_no_sensors",
    "recording",
    "nav_truth_rpp",
    "nav_ekf_mppi",
)


def test_one_floor_and_every_figure_a_ratio_against_it_with_its_spread():
    from amr_twin.bench.figures import report_lines

    r = run_benchmarks(load_config(), sim_s=0.2, repeats=2)
    assert r["timer"] == "process_time" and r["repeats"] == 2
    assert set(FIGURES) <= set(r["figures"]) and list(r["figures"])[0] == "loop"
    floor = r["floor"]["s_per_sim_s"]
    # a floor before each round and after each figure in it, all in the floor's spread
    assert (
        len(floor["repeats"]) == 2 * (len(r["figures"]) + 1)
        and floor["min"] <= floor["median"] <= floor["max"]
    )
    assert r["floor"]["us_per_step"]["median"] == pytest.approx(floor["median"] * 1e3, rel=1e-3)
    for name, fig in r["figures"].items():
        ratio = fig["ratio"]
        assert (
            len(ratio["repeats"]) == 2
            and ratio["min"] <= ratio["q1"] <= ratio["median"] <= ratio["q3"] <= ratio["max"]
        )
        assert ratio["median"] == pytest.approx(statistics.median(ratio["repeats"]), abs=1e-3), name
        assert fig["what"]
    assert all(len(v) == 3 for v in r["load_average"].values())
    d = r["details"]
    assert d["lidar_beams_per_scan"] == 364 and d["collisions"] == 0 and d["rrd_bytes"] > 0
    assert set(d["native_engines"]) == {
        "grid_steps",
        "rolling_resistance",
        "battery",
        "collisions",
        "actors",
        "hall_edges",
        "imu_errors",
        "lidar_beams",
        "tyres",
        "mppi_critics",
        "drive_arcs",
    }
    assert all(e == "C" or e.startswith("Python (") for e in d["native_engines"].values())
    assert d["actors_engine"] == d["native_engines"]["actors"]
    assert "avr_skipped" in d or "avr" in r["figures"]
    assert 0 < d["nav_plan_ms_p50"] <= d["nav_plan_ms_p95"] and d["nav_plans"] == 30
    assert (
        0 < d["nav_mppi_ms_p50"] <= d["nav_mppi_ms_p99"]
        and 0 < d["nav_rpp_ms_p50"] <= d["nav_rpp_ms_p99"]
    )
    text = report_lines(r)
    assert sum(line.startswith("floor:") for line in text) == 1 and "load average" in text[1]
    assert all(any(line.startswith(f"{name} ") for line in text) for name in r["figures"])


def test_spread_and_paired_ratios():
    from amr_twin.bench.physics import spread
    from amr_twin.bench.rounds import ratio_spread

    s = spread([3.0, 1.0, 2.0, 10.0])
    assert (s.median, s.low, s.high, s.q1, s.q3) == (2.5, 1.0, 10.0, 1.75, 4.75) and s.values == (
        3.0,
        1.0,
        2.0,
        10.0,
    )
    one = spread([4.0])
    assert (one.median, one.low, one.high, one.q1, one.q3) == (4.0,) * 5
    with pytest.raises(ValueError):
        spread([])
    # paired: each run over the floor measured right after it, not the medians' ratio
    # (here 2.0 / 1.0 against 1.5)
    r = ratio_spread([2.0, 3.0, 6.0], [1.0, 3.0, 2.0])
    assert r.values == (2.0, 1.0, 3.0) and r.median == 2.0
    with pytest.raises(ValueError, match="3 runs against 2 floors"):
        ratio_spread([1.0, 2.0, 3.0], [1.0, 2.0])


def test_rounds_put_each_figure_between_two_floors(monkeypatch):
    """F L F A F in every round, each ratio over the mean of the floors either side of it; the
    floor's figure spans all its measurements (stand-in runs and floors: no timing)."""
    from amr_twin.bench import rounds as rd
    from amr_twin.bench.physics import FloorPath
    from amr_twin.bench.twin import Timed

    order = []
    floors = iter([1.0, 3.0, 5.0, 2.0, 2.0, 2.0, 4.0, 4.0, 8.0])
    physics = type("P", (), {"timestep_s": 0.001})()

    def run(name, cpu):
        def go(cfg, sim_s):
            order.append(name)
            twin = type("T", (), {"physics": physics})()
            return Timed(cpu * sim_s, sim_s, twin, FloorPath([(None, 1000)]))

        return go

    monkeypatch.setattr(rd, "loop_run", run("loop", 3.0))
    monkeypatch.setattr(rd, "floor_s", lambda path: order.append("floor") or next(floors))
    figs = (rd.Figure("a", "", run("a", 4.0)),)
    got = rd.run_rounds(None, 2.0, figs, repeats=3)
    # the path's loop run and the warm-up first, untimed
    assert order == ["loop", "a"] + ["floor", "loop", "floor", "a", "floor"] * 3
    assert got.cpu == {"loop": [3.0, 3.0, 3.0], "a": [4.0, 4.0, 4.0]}
    # each the mean of its two neighbours (floor_s / (1000 steps * 1 ms))
    assert got.floor == {"loop": [2.0, 2.0, 4.0], "a": [4.0, 2.0, 6.0]}
    out = rd.summary(got, 0.001)
    assert out["figures"]["loop"]["ratio"]["repeats"] == [1.5, 1.5, 0.75]
    assert out["figures"]["a"]["ratio"]["repeats"] == [1.0, 2.0, 0.667]
    assert out["figures"]["a"]["ratio"]["median"] == 1.0
    floor = out["floor"]["s_per_sim_s"]
    assert floor["median"] == 3.0 and floor["max"] == 8.0 and len(floor["repeats"]) == 9
    assert out["floor"]["us_per_step"]["median"] == 3000.0


def test_the_floor_steps_the_loops_own_path():
    """The snapshots cover every step the twin took, piece by piece, stepping them leaves the twin
    as it was, and another run of the scenario drives the same path (one serves every round)."""
    from amr_twin.bench.physics import PIECES, floor_s
    from amr_twin.bench.twin import loop_run

    run = loop_run(load_config(), 0.8)
    twin, path = run.twin, run.path
    assert len(path.pieces) == PIECES and path.steps == twin.t_phys_us // twin.dt_us
    assert [round(p.time_s * 1e6) for p, _n in path.pieces][0] == 0
    first, n = path.pieces[0]
    before = (twin.physics.time_s, first.time_s)
    assert floor_s(path) > 0 and (twin.physics.time_s, first.time_s) == before
    clone = first.clone()
    clone.step(n)
    assert clone.time_s == pytest.approx(path.pieces[1][0].time_s, abs=1e-9)
    # the floor drives where the loop drove: held actuation, within 5 cm of the next snapshot
    assert abs(clone.pose().x_m - path.pieces[1][0].pose().x_m) < 0.05
    again = loop_run(load_config(), 0.8).path
    assert [n for _p, n in again.pieces] == [n for _p, n in path.pieces]
    pairs = zip(again.pieces, path.pieces)
    assert all((p.data.qpos == q.data.qpos).all() for (p, _), (q, _) in pairs)


@pytest.mark.parametrize(
    "args, text", [(["--jobs", "0"], "--jobs 0"), (["--sim-s", "-1"], "--sim-s -1")]
)
def test_bench_refuses_bad_options_in_one_line(args, text):
    from typer.testing import CliRunner

    from amr_twin.cli.main import app

    res = CliRunner().invoke(app, ["bench", *args])
    assert res.exit_code == 2 and text in res.output and len(res.output.strip().splitlines()) == 1


def test_suite_figures_of_a_cheap_stand_in(monkeypatch):
    """The acceptance figures' helpers on tiny stand-ins: fresh processes timed by their own
    rusage, the rrd figure from two captured runs (not timed against targets here)."""
    from amr_twin.bench import suites as sb

    fig = sb.startup_figures(repeats=1)
    assert 0 < fig["help_cpu_s"] < fig["run_1s_cpu_s"]
    monkeypatch.setattr(sb, "RRD_DURATIONS_S", (0.5, 2.0))
    rrd = sb.rrd_figures(load_config(), repeats=1)
    assert rrd["rrd_write_60s_s"] > 0 and rrd["rrd_write_ratio_240_60"] > 0


def test_the_benchmark_scenario_touches_nothing_but_the_floor():
    """The bare figure steps on from where the twin ended: a robot pressed against a rack there
    would make the floor of every ratio unrepresentative (it did, from the old start)."""
    from amr_twin.bench.twin import twin_run

    twin = twin_run(load_config(), 16.0, sensors=True).twin
    assert twin.collisions.collisions == []
    assert twin.physics.pose().x_m - (-8.0) > 10.0  # it drove the whole 11 m down the aisle
    assert (
        twin.sensors["lidar"].last_hit_geom >= 0
    ).mean() > 0.95  # walls and racks in range of the LiDAR


def test_the_actors_benchmark_touches_nothing_and_its_actors_move_in_the_lidars_view():
    from amr_twin.bench.actors import actors_run

    twin = actors_run(load_config(), 16.0).twin
    assert twin.collisions.collisions == []
    assert twin.actors.progress_s() == [16.0, 15.5, 16.0, 16.0]  # none waited
    hit = {
        int(twin.physics.model.geom_bodyid[g])
        for g in twin.sensors["lidar"].last_hit_geom
        if g >= 0
    }
    bodies = {twin.physics.model.body(f"{a.kind}_{i}").id for i, a in enumerate(twin.actors.actors)}
    # the person crossing the aisle ahead is in sight of the last scan (the side aisles' actors come
    # and go behind the racks as the faithful firmware's dead zone lets the heading drift 5-15 deg)
    assert twin.physics.model.body("person_3").id in hit & bodies


def test_timed_children_cache_their_bytecode_outside_the_tree(tmp_path, monkeypatch):
    """Start-up is timed as a user's second start: with PYTHONDONTWRITEBYTECODE set (as on this
    sandbox), a child given the bench's environment still caches the package's bytecode, in the
    bench's own folder and not beside the sources."""
    import subprocess
    import sys
    from pathlib import Path

    import amr_twin
    from amr_twin.bench import suites as sb

    monkeypatch.setenv("PYTHONDONTWRITEBYTECODE", "1")
    tree = Path(amr_twin.__file__).parent
    before = sorted(tree.rglob("*.pyc"))
    cache = tmp_path / "pycache"
    subprocess.run(
        [sys.executable, "-c", "import amr_twin.bench.suites"],
        check=True,
        env=sb._child_env(str(cache)),
    )
    cached = {p.name.split(".")[0] for p in cache.rglob("*.pyc") if "amr_twin" in p.parts}
    assert {"suites", "physics", "config"} <= cached
    assert sorted(tree.rglob("*.pyc")) == before


def test_sweep_rounds_run_in_fresh_processes_and_the_figure_is_their_median(monkeypatch):
    """The sweep figure: each round a process of its own that sweeps and then steps bare physics;
    the figures are the medians of the rounds (a stand-in sweep of two 0.3 s points, three
    rounds)."""
    import os

    from amr_twin.bench import suites as sb

    pids, real = [], sb._sweep_round

    def spy(args, env):
        row = real(args, env)
        pids.append(row["pid"])
        return row

    monkeypatch.setattr(sb, "_sweep_round", spy)
    spec = {
        "masses": [0.0, 10.0],
        "positions": ["center"],
        "commands": ["linear:0.7"],
        "duration_s": 0.3,
    }
    fig = sb.sweep_figures(load_config(), repeats=3, spec=spec)
    assert len(set(pids)) == 3 and os.getpid() not in pids
    rounds = fig["sweep_cpu_s_rounds"]
    assert len(rounds) == 3 and fig["sweep_cpu_s"] == sorted(rounds)[1] and fig["sweep_points"] == 2
    assert (
        fig["sweep_simulated"] == 2
        and 0 < fig["sweep_point_bare_physics_s"] < fig["sweep_point_cpu_s"]
    )


def test_the_suites_say_each_stage_as_it_starts(monkeypatch):
    """bench --suites runs for minutes: each stage is announced before it runs (stand-in stages)."""
    from types import SimpleNamespace

    from amr_twin.bench import suites as sb
    from amr_twin.experiments.fusion import experiment as fusion

    said, ran = [], []

    def stage(name, figures):
        def run(*args, **kwargs):
            ran.append((name, len(said)))
            return figures

        return run

    monkeypatch.setattr(sb, "startup_figures", stage("startup", {"help_cpu_s": 0.1}))
    monkeypatch.setattr(sb, "chapter5_jobs_figures", stage("chapter5", {}))
    monkeypatch.setattr(sb, "sweep_figures", stage("sweep", {}))
    monkeypatch.setattr(sb, "rrd_figures", stage("rrd", {}))
    monkeypatch.setattr(fusion, "run", stage("fusion", SimpleNamespace(sim_s=1.0)))
    monkeypatch.setattr(sb, "ros1_stage", stage("ros1", {}))
    out = sb.suite_figures(load_config(), jobs=2, progress=said.append)
    assert [name for name, _ in ran] == ["startup", "chapter5", "sweep", "rrd", "fusion", "ros1"]
    assert [n for _, n in ran] == [1, 2, 3, 4, 5, 6]  # each announced just before it ran
    assert "sweep" in said[2] and ".rrd" in said[3] and out["help_cpu_s"] == 0.1
