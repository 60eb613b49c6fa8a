"""Executors: the payload sweep on a Dask LocalCluster gives the local numbers and resumes; clear
errors.

The cluster runs its two workers as processes (``processes=True``), so the work
items and the function really travel by pickle to other interpreters, as on a
remote cluster; one cluster serves the whole module.
"""

import json
import math
import socket
import sys

import pytest
from typer.testing import CliRunner

from amr_twin.cli.main import app
from amr_twin.model.config import load_config
from amr_twin.base import process_pool
from amr_twin.experiments.runner import dask_cluster, executor
from amr_twin.experiments.payload import sweep as ps
from amr_twin.experiments.payload.point import Point
from amr_twin.recording.run import warm_up

DURATION_S = 1.5
SWEEP = dict(positions=["center"], commands=["linear:0.7"], duration_s=DURATION_S, progress=False)


@pytest.fixture(scope="module")
def cluster():
    distributed = pytest.importorskip("distributed")
    with distributed.LocalCluster(
        n_workers=2, threads_per_worker=1, processes=True, dashboard_address=":0"
    ) as local_cluster:
        yield local_cluster


@pytest.fixture(scope="module")
def client(cluster):
    c = dask_cluster.connect_dask(cluster.scheduler_address, timeout_s=10.0)
    yield c
    c.close()


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _numbers(row: dict) -> dict:
    return {
        k: v for k, v in row.items() if k != "wall_s"
    }  # wall time is the only non-simulated field


def test_dask_sweep_equals_local_and_rerun_skips_finished(client, tmp_path):
    cfg = load_config()
    local = ps.run(cfg, tmp_path / "local", masses=[0.0, 20.0], jobs=1, **SWEEP)
    on_dask = ps.run(cfg, tmp_path / "dask", masses=[0.0, 20.0], client=client, **SWEEP)
    assert (on_dask["simulated"], on_dask["reused"]) == (2, 0)
    assert [_numbers(r) for r in on_dask["rows"]] == [_numbers(r) for r in local["rows"]]
    light, heavy = on_dask["rows"]
    assert heavy["total_mass_kg"] == pytest.approx(light["total_mass_kg"] + 20.0)
    assert heavy["dyn_min_wheel_n"] > light["dyn_min_wheel_n"]  # the points really differ
    files = sorted(p.name for p in (tmp_path / "dask" / "runs").iterdir())
    assert files == sorted(
        f"{Point(m, 'center', 'linear:0.7', DURATION_S, 'faithful', cfg).key}.json"
        for m in (0.0, 20.0)
    )  # one whole file per point, no temporary left
    again = ps.run(cfg, tmp_path / "dask", masses=[0.0, 20.0], client=client, **SWEEP)
    assert (again["simulated"], again["reused"]) == (0, 2)


def test_dask_samples_equal_local_and_resume(client, tmp_path):
    """With drawn parameters the cluster gives the local numbers too; the run keys carry the
    draws."""
    from amr_twin.calibration.uncertainty import ParameterSpace

    cfg = load_config()
    draws = ParameterSpace.load().draw(2, seed=5)
    local = ps.run(cfg, tmp_path / "local", masses=[20.0], jobs=1, draws=draws, **SWEEP)
    on_dask = ps.run(cfg, tmp_path / "dask", masses=[20.0], client=client, draws=draws, **SWEEP)
    assert [_numbers(r) for r in on_dask["rows"]] == [_numbers(r) for r in local["rows"]]
    assert [r.get("sample") for r in on_dask["rows"]] == [None, 0, 1]
    again = ps.run(cfg, tmp_path / "dask", masses=[20.0], client=client, draws=draws, **SWEEP)
    assert (again["simulated"], again["reused"]) == (0, 3)


def test_cli_dask_does_only_the_missing_points(cluster, tmp_path):
    cfg = load_config()
    done = Point(0.0, "center", "linear:0.7", DURATION_S, "faithful", cfg)
    (tmp_path / "runs").mkdir()
    marker = {
        "key": done.key,
        "fingerprint": done.fingerprint,
        "mass_kg": 0.0,
        "position": "center",
        "command": "linear:0.7",
        "valid": True,
        "error": "",
        "safe": True,
    }
    (tmp_path / "runs" / f"{done.key}.json").write_text(json.dumps(marker))
    result = CliRunner().invoke(
        app,
        [
            "sweep",
            "payload",
            "--out",
            str(tmp_path),
            "--masses",
            "0,10",
            "--positions",
            "center",
            "--commands",
            "linear:0.7",
            "--duration-s",
            str(DURATION_S),
            "--executor",
            "dask",
            "--scheduler",
            cluster.scheduler_address,
        ],
    )
    assert result.exit_code == 0, result.output
    assert "1 simulated, 1 reused" in result.output and "dask tcp://" in result.output
    row = json.loads((tmp_path / "runs" / "m10kg_center_linear_0.7.json").read_text())
    assert row["mass_kg"] == 10.0 and row["valid"] and not row["error"]
    assert (tmp_path / "sweep.csv").exists() and not list(tmp_path.rglob(".*.tmp"))


def test_a_failing_run_on_dask_raises_here(client):
    with pytest.raises(ValueError, match="math domain error"):
        list(
            executor.run_all(
                math.sqrt, [4.0, -1.0, 9.0], description="sqrt", progress=False, client=client
            )
        )
    got = dict(executor.run_all(math.sqrt, [4.0, 9.0], progress=False, client=client))
    assert got == {4.0: 2.0, 9.0: 3.0}


@pytest.mark.parametrize("jobs", [1, 2])
def test_local_executor_same_contract(jobs):
    with pytest.raises(ValueError, match="math domain error"):
        list(executor.run_all(math.sqrt, [4.0, -1.0, 9.0], jobs=jobs, progress=False))
    assert dict(executor.run_all(math.sqrt, [4.0, 9.0, 16.0], jobs=jobs, progress=False)) == {
        4.0: 2.0,
        9.0: 3.0,
        16.0: 4.0,
    }


def test_unreachable_scheduler_is_one_line_error(tmp_path):
    pytest.importorskip("distributed")
    address = f"tcp://127.0.0.1:{_free_port()}"
    with pytest.raises(
        dask_cluster.ExecutorError, match="cannot reach the Dask scheduler within 0.5 s"
    ):
        dask_cluster.connect_dask(address, timeout_s=0.5)
    result = CliRunner().invoke(
        app,
        [
            "sweep",
            "payload",
            "--out",
            str(tmp_path / "s"),
            "--executor",
            "dask",
            "--scheduler",
            address,
            "--scheduler-timeout-s",
            "0.5",
        ],
    )
    assert result.exit_code == 2 and "cannot reach the Dask scheduler" in result.output
    assert len(result.output.strip().splitlines()) == 1
    assert not (tmp_path / "s").exists()


def test_dask_not_installed(monkeypatch):
    monkeypatch.setitem(sys.modules, "distributed", None)  # import distributed -> ImportError
    with pytest.raises(dask_cluster.ExecutorError, match="not installed"):
        dask_cluster.connect_dask("tcp://127.0.0.1:8786")


@pytest.mark.parametrize(
    "args, needle",
    [
        (["--executor", "dask"], "--scheduler"),
        (["--executor", "ray"], "--executor 'ray'"),
        (["--scheduler", "tcp://127.0.0.1:8786"], "only used with --executor dask"),
        (
            [
                "--executor",
                "dask",
                "--scheduler",
                "tcp://127.0.0.1:8786",
                "--scheduler-timeout-s",
                "0",
            ],
            "(0, 3600)",
        ),
    ],
)
def test_cli_rejects_bad_executor_options(tmp_path, args, needle):
    result = CliRunner().invoke(app, ["sweep", "payload", "--out", str(tmp_path / "s"), *args])
    assert result.exit_code == 2 and needle in result.output
    assert not (tmp_path / "s").exists()


def test_jobs_default_to_the_usable_cores_and_are_bounded():
    cores = process_pool.usable_cores()
    assert process_pool.check_jobs(None) == cores and process_pool.check_jobs(1) == 1
    for bad in (0, cores + 1, 1000):
        with pytest.raises(
            ValueError, match=rf"--jobs {bad}: must be in 1..{cores} on this machine"
        ):
            process_pool.check_jobs(bad)
    result = CliRunner().invoke(app, ["sweep", "payload", "--out", "never", "--jobs", "1000"])
    assert result.exit_code == 2 and "usable cores" in result.stderr


def test_a_non_scheduler_or_malformed_address_is_one_line_without_a_hang(tmp_path):
    import subprocess
    import threading
    import time

    pytest.importorskip("distributed")
    server = socket.socket()
    server.bind(("127.0.0.1", 0))
    server.listen(4)

    def babble():  # accepts and answers garbage, as a proxy or another service would
        while True:
            try:
                conn, _ = server.accept()
            except OSError:
                return
            conn.sendall(b"HTTP/1.1 400 Bad Request\r\n\r\n" + bytes(range(256)) * 4)
            time.sleep(0.2)
            conn.close()

    threading.Thread(target=babble, daemon=True).start()
    address = f"tcp://127.0.0.1:{server.getsockname()[1]}"
    code = (
        "from amr_twin.experiments.runner.dask_cluster import connect_dask, ExecutorError\n"
        "try:\n    connect_dask({!r}, 1.0)\nexcept ExecutorError as e:\n    print(e)\n"
    )
    try:
        for addr, text in (
            (address, "no Dask scheduler answered there"),
            ("foo", "not a scheduler address"),
        ):
            t0 = time.perf_counter()
            proc = subprocess.run(
                [sys.executable, "-c", code.format(addr)],
                capture_output=True,
                text=True,
                timeout=60,
            )
            assert text in proc.stdout and proc.stdout.count("\n") == 1
            assert "Traceback" not in proc.stderr and "Exception ignored" not in proc.stderr
            assert time.perf_counter() - t0 < 8.0  # no 10 s finaliser
    finally:
        server.close()


def _children(pid):
    import os

    out = []
    for stat in os.listdir("/proc"):
        if stat.isdigit():
            try:
                fields = open(f"/proc/{stat}/stat").read().rsplit(")", 1)[1].split()
            except OSError:
                continue
            if int(fields[1]) == pid and fields[0] != "Z":
                out.append(int(stat))
    return out


def _kill_and_check_no_worker_survives(command, n_children):
    """Start ``command``, wait for ``n_children`` children (workers, resource tracker), kill -9
    the parent, then every child must be gone within 10 s."""
    import os
    import signal
    import subprocess
    import time

    parent = subprocess.Popen(command, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        deadline = time.monotonic() + 90
        while len(_children(parent.pid)) < n_children and time.monotonic() < deadline:
            time.sleep(0.2)
        workers = _children(parent.pid)
        assert len(workers) >= n_children
        time.sleep(3.0)  # the workers are busy
    finally:
        parent.send_signal(signal.SIGKILL)
        parent.wait()
    deadline = time.monotonic() + 10
    alive = workers
    while alive and time.monotonic() < deadline:
        time.sleep(0.2)
        alive = [
            w
            for w in workers
            if os.path.exists(f"/proc/{w}")
            and open(f"/proc/{w}/stat").read().rsplit(")", 1)[1].split()[0] != "Z"
        ]
    assert alive == []


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads /proc")
def test_pool_workers_die_with_their_parent():
    script = (
        "import time\nfrom amr_twin.experiments.runner.executor import run_all\n"
        "list(run_all(time.sleep, [60.0, 60.0, 60.0, 60.0], jobs=3, progress=False))\n"
    )
    _kill_and_check_no_worker_survives(
        [sys.executable, "-c", script], 3
    )  # 2 workers + resource tracker


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads /proc")
def test_calibrate_workers_die_with_it(tmp_path):
    """amr-twin calibrate --jobs 2: killed outright, it leaves no worker behind."""
    from pathlib import Path

    cli = Path(sys.executable).with_name("amr-twin")
    _kill_and_check_no_worker_survives(
        [
            str(cli),
            "calibrate",
            "--jobs",
            "2",
            "--max-evaluations",
            "7",
            "--out",
            str(tmp_path / "p.yaml"),
        ],
        3,
    )


def test_the_caller_and_a_warm_worker_share_the_items(tmp_path, monkeypatch):
    """jobs=2: this process simulates too (the first item at once, before the worker is warm);
    each item is done once; the pool stays warm for the next call."""
    import os

    (tmp_path / "who_runs.py").write_text(
        "import os, time\ndef run(x):\n    time.sleep(0.3)\n    return x, os.getpid()\n"
    )
    monkeypatch.syspath_prepend(str(tmp_path))
    import who_runs

    # workers spawned by earlier tests do not have tmp_path on their sys.path
    process_pool._close_pools()

    got = list(executor.run_all(who_runs.run, list(range(6)), jobs=2, progress=False))
    assert sorted(item for item, _ in got) == list(range(6))
    assert all(item == value for item, (value, _pid) in got)
    assert (
        got[0][1][1] == os.getpid()
    )  # the caller started at once, whether the worker is warm or not
    worker = (
        process_pool._shared_pool(1, warm_up).submit(process_pool._ready).result(timeout=120)
    )  # warm by now
    again = list(executor.run_all(who_runs.run, list(range(20, 28)), jobs=2, progress=False))
    assert sorted(item for item, _ in again) == list(range(20, 28))
    pids = {pid for _, (_, pid) in again}
    assert pids == {os.getpid(), worker}  # the warm worker took items at once, the caller too
