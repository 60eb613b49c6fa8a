"""Output paths checked before any simulation: a bad path costs one line, not the run.

Each command checks every file and folder it will write before it builds the
model: the target is not a folder (for a file) or a file (for a folder), no file
stands where a folder of its path should be, the nearest existing folder accepts
a new file (probed by creating and deleting one: read-only mounts and permissions
are caught, whatever ``os.access`` says), no two outputs name the same path, and no
output is one of the command's inputs (:func:`check_not_inputs`: the same file after
resolving links, hard links included, or a folder holding an input).
The temporaries that killed runs left for the same targets are removed
(:func:`amr_twin.base.atomic_file.remove_stale_temporaries`). Nothing is created: the
folders are made when the files are written.

Failures raise :class:`OutputError` (a ``ValueError``) with one line naming the
option and the path; the CLI prints it and exits 2.
"""

from __future__ import annotations

import os
import tempfile
from pathlib import Path

from amr_twin.base.atomic_file import remove_stale_temporaries


class OutputError(ValueError):
    """An output path cannot be written; one line naming the option and the path."""


def _nearest_existing(path: Path) -> Path:
    for parent in [path, *path.parents]:
        if parent.exists():
            return parent
    return Path(".")


def _probe(option: str, path: Path, folder: Path) -> None:
    """Create and delete a file in ``folder``, or raise OutputError."""
    try:
        fd, name = tempfile.mkstemp(prefix=".amr-twin-probe.", dir=folder)
        os.close(fd)
        os.unlink(name)
    except OSError as exc:
        raise OutputError(
            f"{option} {path}: cannot write in {folder} ({exc.strerror or exc})"
        ) from None


def _parent_folder(option: str, path: Path) -> Path:
    """The nearest existing ancestor folder of ``path`` (a file in the way is an error)."""
    existing = _nearest_existing(path.parent)
    if not existing.is_dir():
        raise OutputError(f"{option} {path}: {existing} is a file, not a folder")
    return existing


def check_file(option: str, path: Path | str) -> Path:
    """A file output: writable, not a folder, not a device; its stale temporaries removed."""
    path = Path(path)
    if path.name in ("", ".", ".."):
        raise OutputError(f"{option} {path}: give a file name")
    if path.is_dir():
        raise OutputError(f"{option} {path}: is a folder; give a file name")
    if path.exists() and not path.is_file():
        raise OutputError(f"{option} {path}: exists and is not a regular file")
    folder = _parent_folder(option, path)
    _probe(option, path, folder)
    if folder == path.parent:
        remove_stale_temporaries(folder, path.name)
    return path


def check_folder(option: str, path: Path | str) -> Path:
    """A folder output (files written inside): writable, not a file; stale temporaries inside
    removed."""
    path = Path(path)
    if path.exists() and not path.is_dir():
        raise OutputError(f"{option} {path}: exists and is not a folder")
    folder = path if path.is_dir() else _parent_folder(option, path)
    _probe(option, path, folder)
    if folder == path:
        remove_stale_temporaries(path)
    return path


def check_distinct(outputs: dict[str, Path | str | None]) -> None:
    """Refuse two options naming the same path."""
    seen: dict[Path, str] = {}
    for option, path in outputs.items():
        if path is None:
            continue
        resolved = Path(path).resolve()
        for other_path, other in seen.items():
            if resolved == other_path:
                raise OutputError(
                    f"{other} and {option} both name {path}: give each output its own path"
                )
        seen[resolved] = option


def check_outputs(
    files: dict[str, Path | str | None] | None = None,
    folders: dict[str, Path | str | None] | None = None,
) -> None:
    """Check file and folder outputs (option -> path, None = not given) and that they differ."""
    files, folders = files or {}, folders or {}
    for option, path in files.items():
        if path is not None:
            check_file(option, path)
    for option, path in folders.items():
        if path is not None:
            check_folder(option, path)
    check_distinct(files)  # two files on one path: the last write would win
    for f_option, f_path in files.items():  # a file where a folder output goes
        for d_option, d_path in folders.items():
            if (
                f_path is not None
                and d_path is not None
                and Path(f_path).resolve() == Path(d_path).resolve()
            ):
                raise OutputError(
                    f"{f_option} and {d_option} both name {f_path}: give each output its own path"
                )


def same_file(a: Path | str, b: Path | str) -> bool:
    """``a`` and ``b`` are one file: the same path once links are resolved, or (both existing) the
    same inode on the same device, which catches hard links and bind mounts."""
    a, b = Path(a), Path(b)
    if a.resolve() == b.resolve():
        return True
    try:
        sa, sb = a.stat(), b.stat()
    except OSError:
        return False
    return (sa.st_dev, sa.st_ino) == (sb.st_dev, sb.st_ino)


def _holds(folder: Path, path: Path) -> bool:
    """``path`` lies inside ``folder`` (links resolved; a folder that does not exist yet holds
    nothing)."""
    if not folder.is_dir():
        return False
    folder, path = folder.resolve(), path.resolve()
    return folder in path.parents


def _pairs(items) -> list:
    return list(items.items()) if isinstance(items, dict) else list(items)


def check_not_inputs(
    outputs: dict[str, Path | str | None] | list[tuple[str, Path | str | None]],
    inputs: dict[str, Path | str | None] | list[tuple[str, Path | str | None]],
) -> None:
    """Refuse an output that is an input, or a folder output that holds one (its files could replace
    it).

    ``outputs`` and ``inputs``: option (``--csv``; ``--config (default)`` for an input the command
    reads without being told) -> path, None = not given; or a list of such pairs (an option given
    twice). Raises :class:`OutputError` naming both.
    """
    for o_label, o_path in _pairs(outputs):
        if o_path is None:
            continue
        for i_label, i_path in _pairs(inputs):
            if i_path is None:
                continue
            if same_file(o_path, i_path):
                how = (
                    ""
                    if Path(o_path).resolve() == Path(i_path).resolve()
                    else " (the same file by another name)"
                )
                raise OutputError(
                    f"{o_label} {o_path}: is the input {i_label} {i_path}{how}; writing it would "
                    f"destroy it: give {o_label} another path"
                )
            if _holds(Path(o_path), Path(i_path)):
                raise OutputError(
                    f"{o_label} {o_path}: holds the input {i_label} {i_path}; the files written "
                    f"there "
                    f"could replace it: give {o_label} a folder of its own"
                )
