"""The on-disk cache of derived files: the robot's URDF and the parsed parameter files.

Both are keyed by a hash of everything they are made from, so a stale entry is never
read (a changed file has another key); entries are written whole (a temporary file,
then one rename) and a cache that cannot be read or written is skipped, never an error.
The folder is ``$AMR_TWIN_CACHE_DIR`` (:data:`CACHE_ENV`; empty: no disk cache), else
``$XDG_CACHE_HOME/amr-twin`` or ``~/.cache/amr-twin``.
"""

from __future__ import annotations

import contextlib
import os
import tempfile
from pathlib import Path

CACHE_ENV = "AMR_TWIN_CACHE_DIR"
"""Environment variable naming the cache's folder; an empty value turns the disk cache off."""


def cache_dir(kind: str) -> Path | None:
    """The folder of one kind of cache entry (``urdf``, ``yaml``), or None when the disk cache is
    off."""
    configured = os.environ.get(CACHE_ENV)
    if configured is not None:
        return Path(configured) / kind if configured.strip() else None
    base = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(base) / "amr-twin" / kind


def read_entry(path: Path | None) -> bytes | None:
    """The bytes of a cache entry, or None (no cache, no entry, unreadable)."""
    if path is None:
        return None
    try:
        return path.read_bytes()
    except OSError:
        return None


def store(path: Path, data: bytes) -> None:
    """Write a cache entry whole (temporary file, then rename); one that cannot be written is
    skipped."""
    tmp = None
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
        with os.fdopen(fd, "wb") as fh:
            fh.write(data)
        os.replace(tmp, path)
    except OSError:
        if tmp is not None:
            with contextlib.suppress(OSError):
                os.unlink(tmp)
