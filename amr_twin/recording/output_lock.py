"""Locks on outputs in use: a second command writing the same file or folder refuses at once.

Every output of a command (a file or a folder) is locked for as long as the command runs, by
an exclusive ``flock`` on ``.<name>.amr-twin.lock`` beside it (in its parent folder, so that a
folder output is locked before it exists and a file output without touching it). The lock
file holds the holder's pid and start time; a second command asking for it refuses in one line
naming the output and that pid (it does not wait: a sweep that waited would then find every
point done and redo nothing, a waste of the wait). The kernel drops the lock of a process that
dies, however it dies: the next command takes a killed holder's lock over. The lock file is
removed on release, and so are the parent folders made for it that stayed empty, and, when the
command failed, the output folders it made and left empty.
"""

from __future__ import annotations

import fcntl
import os
import time
from contextlib import contextmanager
from pathlib import Path
from typing import Iterator


class OutputBusy(ValueError):
    """An output is locked by another running command; one line naming it and the holder's pid."""


def lock_path(path: Path | str) -> Path:
    """The lock file of output ``path`` (links resolved): ``.<name>.amr-twin.lock`` beside it."""
    path = Path(path).resolve()
    return path.with_name(f".{path.name}.amr-twin.lock")


def _made_parents(folder: Path) -> list[Path]:
    """Create ``folder`` and its missing parents; the ones made, deepest first."""
    missing = [p for p in [folder, *folder.parents] if not p.exists()]
    folder.mkdir(parents=True, exist_ok=True)
    return missing


class OutputLock:
    """The lock of one output (:func:`lock_path`); :meth:`acquire` raises :class:`OutputBusy`."""

    def __init__(self, option: str, path: Path | str):
        self.option, self.path = option, Path(path)
        self.file = lock_path(path)
        self.fd: int | None = None
        self.made: list[Path] = []

    def acquire(self) -> bool:
        """Take the lock; False when it cannot be made (an unwritable folder: the command's own output
        checks say so), OutputBusy when another process holds it."""
        try:
            self.made = _made_parents(self.file.parent)
        except OSError:
            return False
        while True:
            try:
                fd = os.open(self.file, os.O_RDWR | os.O_CREAT, 0o644)
            except OSError:
                self._remove_made()
                return False
            try:
                fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except BlockingIOError:
                holder = os.read(fd, 200).decode(errors="replace").split()
                os.close(fd)
                pid = holder[0] if holder else "unknown"
                since = f", since {holder[1]}" if len(holder) > 1 else ""
                raise OutputBusy(f"{self.option} {self.path}: in use by another amr-twin command (pid {pid}{since}); "
                                 "wait for it to end, or give another path") from None
            try:
                same = os.fstat(fd).st_ino == os.stat(self.file).st_ino
            except FileNotFoundError:  # the holder removed it between our open and our lock
                same = False
            if same:
                break
            os.close(fd)
        os.ftruncate(fd, 0)
        os.write(fd, f"{os.getpid()} {time.strftime('%Y-%m-%dT%H:%M:%S')}\n".encode())
        self.fd = fd
        return True

    def release(self) -> None:
        if self.fd is None:
            return
        try:
            self.file.unlink(missing_ok=True)  # while held: a newcomer's lock on it is checked by inode
        finally:
            os.close(self.fd)
            self.fd = None
            self._remove_made()

    def _remove_made(self) -> None:
        for folder in self.made:  # deepest first; only those still empty
            try:
                folder.rmdir()
            except OSError:
                break
        self.made = []


@contextmanager
def holding(outputs: list[tuple[str, Path]]) -> Iterator[None]:
    """Hold the locks of ``outputs`` (option, path) while the block runs; OutputBusy if one is in use.

    When the block fails, an output folder it made and left empty is removed (a sweep's recording
    folder, made before its first point failed to be written).
    """
    held: list[OutputLock] = []
    files = set()
    new = [Path(path) for _option, path in outputs if not Path(path).exists()]
    try:
        for option, path in outputs:
            if lock_path(path) in files:  # one path given twice (refused by the command): one lock
                continue
            files.add(lock_path(path))
            lock = OutputLock(option, path)
            if lock.acquire():
                held.append(lock)
        yield
    except BaseException:
        for path in new:
            if path.is_dir() and not path.is_symlink() and not any(path.iterdir()):
                path.rmdir()
        raise
    finally:
        for lock in reversed(held):
            lock.release()
