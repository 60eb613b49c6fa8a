"""Locks on outputs in use: a second command writing the same file or folder refuses at once.

Every output of a command (a file or a folder) is locked for as long as the command runs, by an
exclusive ``flock`` on a lock file named after the output's resolved path, in a folder of this
user's locks (:data:`LOCK_DIR`, in the system's temporary folder): nothing appears beside the
outputs, and an output whose folders do not exist yet is locked all the same. The lock file holds
the holder's pid, its start time and the output; a second command asking for it refuses in one
line naming the output and that pid (it does not wait: a sweep that waited would then find every
point done and redo nothing, a waste of the wait). The kernel drops the lock of a process that
dies, however it dies: the next command takes a killed holder's lock over, and removes the lock
files nobody holds. The lock file is removed on release and, when the command failed, so are the
output folders it made and left empty.
"""

from __future__ import annotations

import fcntl
import hashlib
import os
import tempfile
import time
from contextlib import contextmanager
from pathlib import Path
from typing import Iterator


class OutputBusy(ValueError):
    """An output is locked by another running command; one line naming it and the holder's pid."""


LOCK_DIR = Path(tempfile.gettempdir()) / f"amr-twin-locks-{os.getuid()}"
"""Where this user's commands keep the locks of their outputs."""


def lock_path(path: Path | str) -> Path:
    """The lock file of output ``path``: named after its resolved path (links followed as far as it
    exists)."""
    key = hashlib.sha256(str(Path(path).resolve()).encode()).hexdigest()[:32]
    return LOCK_DIR / f"{key}.lock"


def remove_stale_locks() -> list[Path]:
    """Delete the lock files nobody holds (those of killed commands); return them. A file is taken,
    then removed: a command opening it meanwhile sees another inode than the path's and opens the
    path again."""
    removed = []
    for file in LOCK_DIR.glob("*.lock"):
        try:
            fd = os.open(file, os.O_RDWR)
        except OSError:
            continue
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
            if os.fstat(fd).st_ino == os.stat(file).st_ino:
                file.unlink()
                removed.append(file)
        except OSError:  # held by a running command, or gone
            pass
        finally:
            os.close(fd)
    return removed


class OutputLock:
    """The lock of one output (:func:`lock_path`); :meth:`acquire` raises :class:`OutputBusy`."""

    def __init__(self, option: str, path: Path | str):
        self.option, self.path = option, Path(path)
        self.file = lock_path(path)
        self.fd: int | None = None

    def acquire(self) -> bool:
        """Take the lock; False when the lock file cannot be made (no temporary folder: the output
        is then not locked), OutputBusy when another process holds it."""
        try:
            LOCK_DIR.mkdir(mode=0o700, exist_ok=True)
        except OSError:
            return False
        remove_stale_locks()
        while True:
            try:
                fd = os.open(self.file, os.O_RDWR | os.O_CREAT, 0o600)
            except OSError:
                return False
            try:
                fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except BlockingIOError:
                holder = os.read(fd, 200).decode(errors="replace").split()
                os.close(fd)
                pid = holder[0] if holder else "unknown"
                since = f", since {holder[1]}" if len(holder) > 1 else ""
                raise OutputBusy(
                    f"{self.option} {self.path}: in use by another amr-twin command (pid "
                    f"{pid}{since}); "
                    "wait for it to end, or give another path"
                ) from None
            try:
                same = os.fstat(fd).st_ino == os.stat(self.file).st_ino
            except FileNotFoundError:  # the holder removed it between our open and our lock
                same = False
            if same:
                break
            os.close(fd)
        os.ftruncate(fd, 0)
        os.write(
            fd,
            f"{os.getpid()} {time.strftime('%Y-%m-%dT%H:%M:%S')} "
            f"{Path(self.path).resolve()}\n".encode(),
        )
        self.fd = fd
        return True

    def release(self) -> None:
        if self.fd is None:
            return
        try:
            self.file.unlink(
                missing_ok=True
            )  # while held: a newcomer's lock on it is checked by inode
        finally:
            os.close(self.fd)
            self.fd = None


@contextmanager
def holding(outputs: list[tuple[str, Path]]) -> Iterator[None]:
    """Hold the locks of ``outputs`` (option, path) while the block runs; OutputBusy if one is in
    use.

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
