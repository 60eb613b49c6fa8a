"""Output paths checked before the work, files written all together or not at all, stale temporaries
removed."""

import errno
import os
import subprocess
import sys

import pytest
from typer.testing import CliRunner

from amr_twin.base import atomic_file
from amr_twin.base.atomic_file import (
    WriteError,
    all_or_nothing,
    remove_stale_temporaries,
    write_text,
)
from amr_twin.cli.main import app
from amr_twin.recording.outputs import OutputError, check_file, check_folder, check_outputs

runner = CliRunner()


def _dead_pid() -> int:
    proc = subprocess.Popen([sys.executable, "-c", "pass"])
    proc.wait()
    return proc.pid


def test_a_file_output_must_be_a_writable_file_name(tmp_path):
    (tmp_path / "dir").mkdir()
    (tmp_path / "afile").write_text("x")
    with pytest.raises(OutputError, match="is a folder; give a file name"):
        check_file("--csv", tmp_path / "dir")
    with pytest.raises(OutputError, match="afile is a file, not a folder"):
        check_file("--csv", tmp_path / "afile" / "x.csv")
    with pytest.raises(OutputError, match="exists and is not a regular file"):
        check_file("--csv", "/dev/null")
    with pytest.raises(OutputError, match="exists and is not a folder"):
        check_folder("--out", tmp_path / "afile")
    check_file("--csv", tmp_path / "new" / "deeper" / "x.csv")  # folders made when written
    assert not (tmp_path / "new").exists()


def test_an_unwritable_folder_is_found_by_a_probe(tmp_path, monkeypatch):
    def read_only(*args, **kwargs):
        raise OSError(errno.EROFS, "Read-only file system")

    monkeypatch.setattr("tempfile.mkstemp", read_only)
    with pytest.raises(
        OutputError, match=r"--out .*: cannot write in .* \(Read-only file system\)"
    ):
        check_folder("--out", tmp_path)


def test_one_path_for_two_outputs_is_refused(tmp_path):
    with pytest.raises(OutputError, match="--csv and --record both name"):
        check_outputs(files={"--csv": tmp_path / "x", "--record": tmp_path / "x", "--mcap": None})
    res = runner.invoke(
        app, ["run", "stop", "--csv", str(tmp_path / "a"), "--mcap", str(tmp_path / "a")]
    )
    assert (
        res.exit_code == 2
        and "--csv and --mcap both name" in res.stderr
        and not (tmp_path / "a").exists()
    )


def test_files_of_a_batch_appear_together_or_not_at_all(tmp_path, monkeypatch):
    (tmp_path / "b.txt").write_text("old")
    with all_or_nothing():
        write_text(tmp_path / "a.txt", "new a")
        write_text(tmp_path / "b.txt", "new b")
        assert not (tmp_path / "a.txt").exists() and (tmp_path / "b.txt").read_text() == "old"
    assert (tmp_path / "a.txt").read_text() == "new a" and (
        tmp_path / "b.txt"
    ).read_text() == "new b"

    real_write = atomic_file.Path.write_bytes

    def no_space(path, data):
        if path.name.startswith(".c.txt"):
            raise OSError(errno.ENOSPC, "No space left on device")
        return real_write(path, data)

    monkeypatch.setattr(atomic_file.Path, "write_bytes", no_space)
    with pytest.raises(WriteError) as exc:
        with all_or_nothing():
            write_text(tmp_path / "d.txt", "new d")
            write_text(tmp_path / "c.txt", "new c")
    assert exc.value.filename == str(tmp_path / "c.txt") and exc.value.errno == errno.ENOSPC
    assert sorted(p.name for p in tmp_path.iterdir()) == [
        "a.txt",
        "b.txt",
    ]  # no d.txt, no temporaries


def test_a_full_disk_at_the_end_of_a_run_is_one_line_exit_1_and_no_file(tmp_path, monkeypatch):
    import amr_twin.recording.mcap_log as mcap_log

    def no_space(*args, **kwargs):
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(mcap_log, "write_mcap", no_space)
    csv, mcap = tmp_path / "run.csv", tmp_path / "run.mcap"
    res = runner.invoke(
        app,
        [
            "run",
            "linear",
            "--speed-m-s",
            "0.5",
            "--duration-s",
            "0.5",
            "--csv",
            str(csv),
            "--mcap",
            str(mcap),
        ],
    )
    assert res.exit_code == 1 and "No space left on device" in res.stderr
    assert len(res.stderr.strip().splitlines()) == 1
    assert list(tmp_path.iterdir()) == []


def test_stale_temporaries_of_dead_writers_are_removed_live_ones_kept(tmp_path):
    dead, alive = _dead_pid(), os.getppid()
    stale = tmp_path / f".run.rrd.{dead}.tmp"
    live = tmp_path / f".run.rrd.{alive}.tmp"
    other = tmp_path / f".other.csv.{dead}.tmp"
    for p in (stale, live, other):
        p.write_text("half")
    assert remove_stale_temporaries(tmp_path, "run.rrd") == [stale]
    assert live.exists() and other.exists()
    res = runner.invoke(
        app, ["run", "stop", "--duration-s", "0.2", "--csv", str(tmp_path / "other.csv")]
    )
    assert res.exit_code == 0 and not other.exists() and (tmp_path / "other.csv").exists()
