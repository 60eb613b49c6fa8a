"""Whole-or-nothing files (no mujoco)."""

import pytest

from amr_twin.base.atomic_file import replacing, temporary_name, write_text


def test_write_replaces_and_leaves_no_temporary(tmp_path):
    target = tmp_path / "sub" / "a.csv"
    write_text(target, "one\n")
    write_text(target, "two\n")
    assert target.read_text() == "two\n"
    assert [p.name for p in target.parent.iterdir()] == ["a.csv"]


def test_an_error_keeps_the_old_file_and_removes_the_temporary(tmp_path):
    target = tmp_path / "a.json"
    target.write_text("old")
    with pytest.raises(RuntimeError):
        with replacing(target) as tmp:
            tmp.write_text("half")
            assert tmp == temporary_name(target) and tmp.name.startswith(".a.json.")
            raise RuntimeError("interrupted")
    assert target.read_text() == "old"
    assert not temporary_name(target).exists()


def test_a_failed_batch_removes_the_folders_it_made(tmp_path):
    """Chapter 5's --out when its PNG cannot be written: no empty folder is left (nor its
    parents)."""
    from amr_twin.base.atomic_file import all_or_nothing

    with pytest.raises(OSError):
        with all_or_nothing():
            write_text(tmp_path / "out" / "deeper" / "report.md", "text")
            with replacing(tmp_path / "out" / "deeper" / "run1.png"):
                raise OSError(27, "File too large")
    assert list(tmp_path.iterdir()) == []
    (tmp_path / "kept").mkdir()
    with pytest.raises(KeyboardInterrupt):  # interrupted: the same
        with all_or_nothing():
            write_text(tmp_path / "kept" / "new" / "a.csv", "text")
            raise KeyboardInterrupt
    assert [p.name for p in tmp_path.iterdir()] == ["kept"] and list(
        (tmp_path / "kept").iterdir()
    ) == []
