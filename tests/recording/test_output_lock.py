"""An output in use is refused naming its holder; a killed holder's lock is taken over; nothing is
left."""

import os
import signal
import subprocess
import sys
import time

import pytest
from typer.testing import CliRunner

from amr_twin.cli.main import app
from amr_twin.recording.output_lock import OutputBusy, OutputLock, holding, lock_path

runner = CliRunner()
HOLD = (
    "import sys, time\nfrom amr_twin.recording.output_lock import OutputLock\n"
    "OutputLock('--out', sys.argv[1]).acquire()\nprint('held', flush=True)\ntime.sleep(60)\n"
)


@pytest.fixture
def holder(tmp_path):
    """Another process holding the lock of tmp_path / "out" (killed at the end)."""
    proc = subprocess.Popen(
        [sys.executable, "-c", HOLD, str(tmp_path / "out")], stdout=subprocess.PIPE, text=True
    )
    assert proc.stdout.readline().strip() == "held"
    yield proc
    proc.kill()
    proc.wait()


def test_a_second_command_on_an_output_in_use_refuses_naming_the_holder(tmp_path, holder):
    with pytest.raises(
        OutputBusy,
        match=rf"--out .*out: in use by another amr-twin command \(pid {holder.pid}, since ",
    ):
        OutputLock("--out", tmp_path / "out").acquire()
    res = runner.invoke(
        app,
        [
            "sweep",
            "payload",
            "--out",
            str(tmp_path / "out"),
            "--masses",
            "0",
            "--positions",
            "center",
            "--commands",
            "linear:0.5",
            "--no-progress",
        ],
    )
    assert res.exit_code == 2 and f"(pid {holder.pid}," in res.stderr and "--out" in res.stderr
    assert len(res.stderr.strip().splitlines()) == 1
    assert list(tmp_path.iterdir()) == []  # nothing beside the outputs, then or now


def test_a_killed_holder_s_lock_is_taken_over(tmp_path, holder):
    holder.send_signal(signal.SIGKILL)
    holder.wait()
    assert lock_path(tmp_path / "out").exists()  # left behind by the killed process
    lock = OutputLock("--out", tmp_path / "out")
    assert lock.acquire()
    assert lock_path(tmp_path / "out").read_text().split()[0] == str(os.getpid())
    lock.release()
    assert list(tmp_path.iterdir()) == [] and not lock_path(tmp_path / "out").exists()


def test_the_lock_files_of_killed_commands_are_removed_those_held_kept(tmp_path, holder):
    stale = lock_path(tmp_path / "killed")
    stale.write_text("999999 2026-01-01T00:00:00 killed\n")
    with holding([("--csv", tmp_path / "x.csv")]):
        assert not stale.exists()
        assert lock_path(tmp_path / "out").exists()  # the running holder's


def test_the_lock_is_released_and_nothing_is_made_for_it(tmp_path):
    target = tmp_path / "a" / "b" / "run.csv"
    with holding(
        [("--csv", target), ("--mcap", target)]
    ):  # one path twice: one lock, not a self-refusal
        assert lock_path(target).exists() and lock_path(target).read_text().split()[2] == str(
            target
        )
        with pytest.raises(OutputBusy):  # the same output by another name is the same lock
            OutputLock("--csv", tmp_path / "a" / ".." / "a" / "b" / "run.csv").acquire()
    assert not lock_path(target).exists() and list(tmp_path.iterdir()) == []


def test_a_run_holds_its_outputs_until_it_ends(tmp_path):
    """While a run writes run.csv, another command writing it is refused; after it ends, it is
    free."""
    csv = tmp_path / "run.csv"
    cli = [
        sys.executable,
        "-m",
        "amr_twin.cli.main",
        "run",
        "linear",
        "--speed-m-s",
        "0.3",
        "--csv",
        str(csv),
    ]
    first = subprocess.Popen(
        [*cli, "--duration-s", "3600", "--world", "empty"], stderr=subprocess.PIPE, text=True
    )
    try:
        deadline = time.monotonic() + 60
        while not lock_path(csv).exists() and time.monotonic() < deadline:
            time.sleep(0.05)
        res = runner.invoke(app, ["run", "stop", "--duration-s", "0.1", "--csv", str(csv)])
        assert res.exit_code == 2 and f"pid {first.pid}" in res.stderr
    finally:
        first.send_signal(signal.SIGINT)
        first.wait(timeout=60)
    assert not csv.exists() and list(tmp_path.iterdir()) == []  # interrupted: no file, no lock
    res = runner.invoke(app, ["run", "stop", "--duration-s", "0.1", "--csv", str(csv)])
    assert res.exit_code == 0 and csv.exists()


def test_a_failed_command_leaves_no_empty_output_folder(tmp_path):
    """A sweep's recording folder made before its first point failed to be written is removed; a
    folder that was there before, or that holds a file, is kept."""
    (tmp_path / "old").mkdir()
    with pytest.raises(OSError):
        with holding(
            [
                ("--record", tmp_path / "rec"),
                ("--out", tmp_path / "old"),
                ("--mcap", tmp_path / "full"),
            ]
        ):
            for name in ("rec", "full"):
                (tmp_path / name).mkdir()
            (tmp_path / "full" / "a.mcap").write_text("x")
            raise OSError(28, "No space left on device")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["full", "old"]


def test_an_interrupted_chapter5_leaves_none_of_its_recordings(tmp_path):
    """Ctrl-C after a run was recorded (by a pool worker or this process): "no output written" holds
    for the recordings too; none appears under its name before the end (a killed command leaves a
    temporary, never a half ``run<N>.rrd``)."""
    rec = tmp_path / "rec"
    cli = [
        sys.executable,
        "-m",
        "amr_twin.cli.main",
        "experiment",
        "chapter5",
        "--out",
        str(tmp_path / "o"),
        "--record",
        str(rec),
        "--runs",
        "1,2,3",
        "--duration-s",
        "120",
        "--jobs",
        "2",
        "--no-progress",
    ]
    proc = subprocess.Popen(cli, stderr=subprocess.PIPE, text=True)
    try:
        deadline = time.monotonic() + 120
        while not any(".rrd" in p.name for p in (rec.iterdir() if rec.is_dir() else [])):
            assert time.monotonic() < deadline and proc.poll() is None
            time.sleep(0.05)
        time.sleep(0.5)  # the first recording is whole by now
        assert proc.poll() is None and not any(p.name.endswith(".rrd") for p in rec.iterdir())
    finally:
        proc.send_signal(signal.SIGINT)
        _, err = proc.communicate(timeout=60)
    assert proc.returncode == 130 and "interrupted; no output written" in err
    assert not rec.exists() or list(rec.iterdir()) == []
    assert not (tmp_path / "o").exists()
