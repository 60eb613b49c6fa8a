"""Files that appear whole or not at all: write a temporary name next to the target, then rename.

Every writer of the project (CSV and JSON results, plots, parameter files, the
``.rrd`` and ``.mcap`` recordings) goes through :func:`replacing`: the data is
written to ``.<name>.<pid>.tmp`` in the target's folder and moved over the target
with one ``os.replace`` (atomic on POSIX within a file system), so a reader or an
interrupted run never sees half a file. On any error the temporary is removed and
the error (an ``OSError``) names the target, not the temporary.

Several files that belong together (a report and its plots) are written inside
:func:`all_or_nothing`: every temporary is written first, and the renames happen
only when all of them succeeded; a full disk half-way leaves none of the new files,
and no folder made for them (an output folder that would stay empty is removed).

A process killed outright leaves its temporary behind; the pid in the name tells
whether its writer still runs, and :func:`remove_stale_temporaries` deletes those
of dead writers (the CLI does it for each output before a run).
"""

from __future__ import annotations

import os
import shutil
from contextlib import contextmanager
from pathlib import Path
from typing import Iterator

_batch: list[list] = []  # stack of open all_or_nothing() batches: [(tmp, target) renames, cleanups]
_made: list[
    list[Path]
] = []  # per open batch: the folders its writers created (removed if it fails)


def temporary_name(path: str | Path) -> Path:
    """The temporary file ``.<name>.<pid>.tmp`` next to ``path``."""
    path = Path(path)
    return path.with_name(f".{path.name}.{os.getpid()}.tmp")


class WriteError(OSError):
    """Writing an output failed (disk full, read-only); ``filename`` is the target, not the
    temporary."""


def _named(exc: OSError, path: Path) -> WriteError:
    """The same error as a :class:`WriteError` naming ``path`` (the target); a file too large says
    the limit."""
    return WriteError(exc.errno, why(exc.errno, exc.strerror or str(exc)), str(path))


def why(errno_: int | None, strerror: str) -> str:
    """``strerror``, with the file-size limit (``ulimit -f``) when that is what was hit."""
    import errno
    import resource

    limit = resource.getrlimit(resource.RLIMIT_FSIZE)[0]
    if errno_ == errno.EFBIG and limit != resource.RLIM_INFINITY:
        return f"{strerror} (the file-size limit, ulimit -f, is {limit} bytes)"
    return strerror


@contextmanager
def replacing(path: str | Path) -> Iterator[Path]:
    """Yield a temporary path to write; on success it replaces ``path``, on error it is removed.

    The parent folder is created if needed. Inside :func:`all_or_nothing` the rename
    waits for the end of the batch.
    """
    path = Path(path)
    tmp = temporary_name(path)
    deferred = False
    made = [p for p in [path.parent, *path.parent.parents] if not p.exists()]  # deepest first
    if _made:
        _made[-1].extend(made)
    done = False
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        yield tmp
        if _batch:
            _batch[-1].append((tmp, path))
            deferred = True
        else:
            os.replace(tmp, path)
        done = True
    except WriteError:
        raise
    except OSError as exc:
        raise _named(exc, path) from None
    finally:
        if not deferred:
            tmp.unlink(missing_ok=True)
        if not done and not _made:
            remove_empty(made)


def place(written: str | Path, path: str | Path) -> None:
    """Move an already written file ``written`` (same file system) onto ``path``, with the batch."""
    written, path = Path(written), Path(path)
    if _batch:
        _batch[-1].append((written, path))
    else:
        try:
            os.replace(written, path)
        except OSError as exc:
            raise _named(exc, path) from None


def discard_after(path: str | Path) -> None:
    """Remove the staging file or folder ``path`` once the batch is over (now, outside one)."""
    path = Path(path)
    if _batch:
        _batch[-1].append((path, None))
    else:
        _remove(path)


@contextmanager
def all_or_nothing() -> Iterator[None]:
    """Files written inside appear together at the end, or none of them if anything fails."""
    renames: list = []
    _batch.append(renames)
    _made.append([])
    try:
        yield
    except BaseException:
        _batch.pop()
        for tmp, _path in renames:
            _remove(tmp)
        remove_empty(sorted(set(_made.pop()), key=lambda p: len(p.parts), reverse=True))
        raise
    _batch.pop()
    made = _made.pop()
    if _made:  # an outer batch removes them if it fails
        _made[-1].extend(made)
    try:
        for tmp, path in renames:
            if path is not None:
                try:
                    os.replace(tmp, path)
                except OSError as exc:
                    raise _named(exc, path) from None
    finally:
        for tmp, path in renames:
            if path is None or tmp.exists():
                _remove(tmp)


def write_bytes(path: str | Path, data: bytes) -> None:
    """Write ``data`` to ``path`` atomically."""
    with replacing(path) as tmp:
        tmp.write_bytes(data)


def write_text(path: str | Path, text: str) -> None:
    """Write ``text`` (UTF-8) to ``path`` atomically."""
    write_bytes(path, text.encode())


def remove_empty(folders: list[Path]) -> None:
    """Remove the folders (deepest first) that are empty: those a failed write made for nothing."""
    for folder in folders:
        try:
            folder.rmdir()
        except OSError:
            pass


def _remove(path: Path) -> None:
    if path.is_dir() and not path.is_symlink():
        shutil.rmtree(path, ignore_errors=True)
    else:
        path.unlink(missing_ok=True)


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


def remove_stale_temporaries(folder: str | Path, name: str | None = None) -> list[Path]:
    """Delete the temporaries that killed writers left in ``folder``; return them.

    ``name``: only those of that target (``.<name>.<pid>.tmp``); default: all. A
    temporary whose writer still runs (its pid is alive) is left alone.
    """
    folder = Path(folder)
    if not folder.is_dir():
        return []
    removed = []
    for tmp in folder.glob(f".{name}.*.tmp" if name else ".*.tmp"):
        stem, _, pid = tmp.name[1 : -len(".tmp")].rpartition(".")
        if (
            stem
            and (name is None or stem == name)
            and pid.isdigit()
            and int(pid) != os.getpid()
            and not _alive(int(pid))
        ):
            _remove(tmp)
            removed.append(tmp)
    return removed
