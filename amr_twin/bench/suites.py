"""Figures of the waits users see: ``amr-twin bench --suites``.

Each figure is the median of :data:`~amr_twin.bench.physics.REPEATS` interleaved repeats,
except the fusion experiment (one run):

- ``help_cpu_s``, ``run_1s_cpu_s``: CPU time (user + sys) of ``amr-twin --help`` and of a
  1 s ``amr-twin run`` in a fresh process (the imports, the build, the run, the output), as a
  user's second start finds it: Python's bytecode cached (see :func:`_child_env`);
- ``chapter5_wall_s_jobs1`` / ``chapter5_wall_s_jobsN``: wall time of ``amr-twin experiment
  chapter5 --runs 1,...,8`` (132 simulated s) in a fresh process with ``--jobs 1`` and N;
- ``sweep_cpu_s``: CPU time of a 100-point payload sweep (8 s each), each repeat in a fresh
  process (:mod:`amr_twin.bench.sweep_round`; ``sweep_cpu_s_rounds`` lists them);
  ``sweep_point_ratio``: the median of the rounds' CPU per point against bare physics
  (``mj_step``) of the same simulated time on a point's model, timed right after the sweep;
- ``rrd_write_60s_s``, ``rrd_write_240s_s``: CPU time of writing the ``.rrd`` of a 60 s and of
  a 240 s run with sensors (spinning in place in the warehouse), and their ratio;
- ``fusion_wall_s``: the fusion experiment (wall), with the load average around it all.
- ``ros1_*``: the ROS 1 path (:mod:`amr_twin.bench.ros1`): the bridge against the same twin
  without it (a recorder of its topics, or ``-a``), the pacing at ``--rate 1`` over 60 s, a
  ``wheel_Command``'s delay through the board's pty.
"""

from __future__ import annotations

import json
import os
import pickle
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from amr_twin.bench.physics import REPEATS, timer
from amr_twin.bench.sweep_round import SWEEP
from amr_twin.model.config import TwinConfig

RRD_DURATIONS_S = (60.0, 240.0)


def _cli() -> str:
    return str(Path(sys.executable).with_name("amr-twin"))


def _child_env(pycache: str) -> dict:
    """The environment of a timed child: bytecode written to and read from ``pycache``.

    Python caches each module's compiled bytecode on its first import, and every later start
    reads it. An environment that forbids the cache (``PYTHONDONTWRITEBYTECODE``, set on some
    CI and sandbox machines) makes every start compile each module changed since its last cached
    copy (~20 ms for eight of the package's modules here), which no user's second start pays.
    The children cache in a folder of their own (``PYTHONPYCACHEPREFIX``), so the user's tree
    and virtual environment are left as they are, and one untimed warm-up fills it.
    """
    env = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}
    env["PYTHONPYCACHEPREFIX"] = pycache
    return env


def _child_cpu_s(args: list[str], env: dict | None = None) -> float:
    """CPU time (user + sys) of a child process running ``args`` to its end, s."""
    proc = subprocess.Popen(
        args,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
        stdin=subprocess.DEVNULL,
        env=env,
    )
    _pid, status, usage = os.wait4(proc.pid, 0)
    proc.returncode = os.waitstatus_to_exitcode(status)
    if proc.returncode != 0:
        raise RuntimeError(f"benchmark command failed ({proc.returncode}): {' '.join(args)}")
    return usage.ru_utime + usage.ru_stime


def _child_wall_s(args: list[str], env: dict | None = None) -> float:
    t0 = time.perf_counter()
    subprocess.run(
        args,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
        stdin=subprocess.DEVNULL,
        check=True,
        env=env,
    )
    return time.perf_counter() - t0


def startup_figures(repeats: int = REPEATS) -> dict:
    """``help_cpu_s`` and ``run_1s_cpu_s``: medians of interleaved fresh processes (after a
    warm-up)."""
    cli = _cli()
    help_args, run_args = (
        [cli, "--help"],
        [cli, "run", "linear", "--speed-m-s", "0.5", "--duration-s", "1"],
    )
    help_t, run_t = [], []
    with tempfile.TemporaryDirectory(prefix="amr-twin-bench-pycache-") as pycache:
        env = _child_env(pycache)
        for args in (help_args, run_args):  # untimed: fills the bytecode cache
            _child_cpu_s(args, env)
        for _ in range(repeats):
            help_t.append(_child_cpu_s(help_args, env))
            run_t.append(_child_cpu_s(run_args, env))
    return {
        "help_cpu_s": round(statistics.median(help_t), 3),
        "run_1s_cpu_s": round(statistics.median(run_t), 3),
    }


def chapter5_jobs_figures(jobs: int, repeats: int = REPEATS) -> dict:
    """Wall time of the eight chapter 5 runs with ``--jobs 1`` and ``--jobs jobs``, interleaved."""
    cli, walls = _cli(), {1: [], jobs: []}
    with tempfile.TemporaryDirectory(prefix="amr-twin-bench-") as tmp:
        env = _child_env(str(Path(tmp) / "pycache"))
        _child_wall_s(
            [
                cli,
                "experiment",
                "chapter5",
                "--runs",
                "1,2",
                "--jobs",
                str(jobs),
                "--no-progress",
                "--out",
                str(Path(tmp) / "warm"),
            ],
            env,
        )  # untimed: fills the bytecode cache (workers' too)
        for _ in range(repeats):
            for n in walls:
                out = Path(tmp) / f"ch5_{n}"
                walls[n].append(
                    _child_wall_s(
                        [
                            cli,
                            "experiment",
                            "chapter5",
                            "--runs",
                            "1,2,3,4,5,6,7,8",
                            "--jobs",
                            str(n),
                            "--no-progress",
                            "--out",
                            str(out),
                        ],
                        env,
                    )
                )
                shutil.rmtree(out, ignore_errors=True)
    one, many = statistics.median(walls[1]), statistics.median(walls[jobs])
    return {
        "chapter5_wall_s_jobs1": round(one, 2),
        f"chapter5_wall_s_jobs{jobs}": round(many, 2),
        "chapter5_parallel_speedup": round(one / many, 2),
    }


def sweep_figures(cfg: TwinConfig, repeats: int = REPEATS, spec: dict = SWEEP) -> dict:
    """CPU of a 100-point sweep (8 s each; ``spec`` another) and per point against bare physics:
    medians of ``repeats`` rounds, each in a fresh process (:mod:`amr_twin.bench.sweep_round`)."""
    rounds = []
    with tempfile.TemporaryDirectory(prefix="amr-twin-bench-") as tmp:
        path = Path(tmp) / "round.pkl"
        path.write_bytes(pickle.dumps((cfg, spec)))
        env = _child_env(str(Path(tmp) / "pycache"))
        for _ in range(repeats):
            rounds.append(
                _sweep_round([sys.executable, "-m", "amr_twin.bench.sweep_round", str(path)], env)
            )
    cpu, bare = [r["sweep_cpu_s"] for r in rounds], [r["bare_point_s"] for r in rounds]
    n = rounds[0]["points"]
    return {
        "sweep_points": n,
        "sweep_simulated": rounds[0]["simulated"],
        "sweep_cpu_s": round(statistics.median(cpu), 2),
        "sweep_cpu_s_rounds": [round(c, 2) for c in cpu],
        "sweep_point_cpu_s": round(statistics.median(cpu) / n, 3),
        "sweep_point_bare_physics_s": round(statistics.median(bare), 3),
        "sweep_point_ratio": round(statistics.median(c / n / b for c, b in zip(cpu, bare)), 2),
    }


def _sweep_round(args: list[str], env: dict) -> dict:
    """Run one round's process; its JSON line."""
    proc = subprocess.run(args, capture_output=True, text=True, env=env, stdin=subprocess.DEVNULL)
    if proc.returncode != 0:
        last = (proc.stderr.strip().splitlines() or ["no output"])[-1]
        raise RuntimeError(f"sweep round failed ({proc.returncode}): {last}")
    return json.loads(proc.stdout.strip().splitlines()[-1])


def rrd_figures(cfg: TwinConfig, repeats: int = REPEATS) -> dict:
    """CPU of writing the ``.rrd`` of a 60 s and a 240 s run with sensors (interleaved writes)."""
    from amr_twin.assembly.twin import Twin, TwinOptions
    from amr_twin.recording.rerun_capture import attach
    from amr_twin.recording.rerun_log import write_rrd
    from amr_twin.assembly.command import Command
    from amr_twin.recording.run import run_mission

    runs = {}
    for duration in RRD_DURATIONS_S:
        options = TwinOptions(sensors=("imu", "lidar"))
        twin = Twin(cfg, options)
        capture = attach(twin)
        result = run_mission(
            cfg,
            [(0.0, Command("angular", speed_deg_s=30.0, icc_m=0.0))],
            duration,
            options,
            twin=twin,
        )
        runs[duration] = (capture, result)
    times = {d: [] for d in RRD_DURATIONS_S}
    with tempfile.TemporaryDirectory(prefix="amr-twin-bench-") as tmp:
        for _ in range(repeats):
            for duration, (capture, result) in runs.items():
                t0 = timer()
                write_rrd(capture, result.series, Path(tmp) / "run.rrd", result)
                times[duration].append(timer() - t0)
    short, long = (statistics.median(times[d]) for d in RRD_DURATIONS_S)
    return {
        "rrd_write_60s_s": round(short, 3),
        "rrd_write_240s_s": round(long, 3),
        "rrd_write_ratio_240_60": round(long / short, 2),
    }


def ros1_stage(progress=None) -> dict:
    """The ROS 1 figures (:mod:`amr_twin.bench.ros1`; rospy is imported in its child processes
    only)."""
    from amr_twin.bench.ros1 import ros1_figures

    return ros1_figures(progress=progress)


def suite_figures(cfg: TwinConfig, jobs: int = 2, progress=None) -> dict:
    """Every figure of the module notes; takes several minutes on the 2-core machine.

    ``progress(text)``, when given, is told each stage as it starts (the command line prints it
    on stderr)."""
    from amr_twin.experiments.fusion import experiment as fusion

    say = progress or (lambda text: None)
    load_before = os.getloadavg()[0]
    out = {"suites_repeats": REPEATS, "jobs": jobs}
    say(f"start-up: --help and a 1 s run, {REPEATS} each")
    out.update(startup_figures())
    if jobs > 1:
        say(f"chapter 5 with --jobs 1 and {jobs}, {REPEATS} each")
        out.update(chapter5_jobs_figures(jobs))
    say(f"100-point sweep, {REPEATS} rounds of about 20 s of CPU")
    out.update(sweep_figures(cfg))
    say("writing the .rrd of a 60 s and a 240 s run")
    out.update(rrd_figures(cfg))
    say("the fusion experiment")
    t0 = time.perf_counter()
    fus = fusion.run(cfg, progress=False)
    out.update(fusion_sim_s=round(fus.sim_s, 1), fusion_wall_s=round(time.perf_counter() - t0, 2))
    say(
        "ROS 1: the bridge against no bridge, --rate 1 for 60 s, the serial port's latency "
        "(about 3 min)"
    )
    out.update(ros1_stage(progress=say))
    out.update(
        load_average_1min_before=round(load_before, 2),
        load_average_1min_after=round(os.getloadavg()[0], 2),
    )
    return out
