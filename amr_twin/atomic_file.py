"""Files that appear whole or not at all: write a temporary name next to the target, then rename.

Every writer of the project (CSV and JSON results, plots, parameter files, the
``.rrd`` and ``.mcap`` recordings) goes through :func:`replacing`: the data is
written to ``.<name>.<pid>.tmp`` in the target's folder and moved over the target
with one ``os.replace`` (atomic on POSIX within a file system), so a reader or an
interrupted run never sees half a file. On any error the temporary is removed; a
process killed outright leaves it behind, and the pid in its name tells whether
its writer is still running (see :func:`amr_twin.rerun_capture.remove_stale_temporaries`).
"""

from __future__ import annotations

import os
from contextlib import contextmanager
from pathlib import Path
from typing import Iterator


def temporary_name(path: str | Path) -> Path:
    """The temporary file ``.<name>.<pid>.tmp`` next to ``path``."""
    path = Path(path)
    return path.with_name(f".{path.name}.{os.getpid()}.tmp")


@contextmanager
def replacing(path: str | Path) -> Iterator[Path]:
    """Yield a temporary path to write; on success it replaces ``path``, on error it is removed.

    The parent folder is created if needed.
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = temporary_name(path)
    try:
        yield tmp
        os.replace(tmp, path)
    finally:
        tmp.unlink(missing_ok=True)


def write_bytes(path: str | Path, data: bytes) -> None:
    """Write ``data`` to ``path`` atomically."""
    with replacing(path) as tmp:
        tmp.write_bytes(data)


def write_text(path: str | Path, text: str) -> None:
    """Write ``text`` (UTF-8) to ``path`` atomically."""
    write_bytes(path, text.encode())
