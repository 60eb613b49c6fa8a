"""YAML input files (missions, routes, maps) read with one-line errors that name the file.

A missing or unreadable file, a folder or a device, a file over :data:`MAX_YAML_BYTES`, bytes that
are not UTF-8 text, or YAML that does not parse, raises the caller's error class with
``"<kind> <path>: <reason>"`` (the line number of a syntax error included), so the CLI can print it
as is and exit non-zero. Nothing is read past the size bound (``/dev/zero`` is refused, not read).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import yaml


MAX_YAML_BYTES = 16 * 1024 * 1024
"""Largest YAML input read, bytes (a mission of a million steps is ~40 MB of YAML and a long parse)."""


def read_text(path: str | Path, kind: str, error: type[Exception], limit: int = MAX_YAML_BYTES) -> str:
    """The UTF-8 text of a regular file of at most ``limit`` bytes; ``error(f"{kind} {path}: ...")`` otherwise
    (``f"{path}: ..."`` with no ``kind``)."""
    path = Path(path)
    where = f"{kind} {path}" if kind else str(path)
    if path.is_dir():
        raise error(f"{where}: is a folder, not a file")
    if path.exists() and not path.is_file():  # checked before opening: opening a pipe waits for a writer
        raise error(f"{where}: not a regular file (a device or a pipe)")
    try:
        with open(path, "rb") as fh:
            data = fh.read(limit + 1)
    except OSError as exc:
        raise error(f"{where}: {exc.strerror or exc}") from None
    if len(data) > limit:
        raise error(f"{where}: larger than {limit // 1024 // 1024} MB")
    try:
        return data.decode()
    except UnicodeDecodeError as exc:
        raise error(f"{where}: not a text file (byte {exc.start} is not UTF-8)") from None


def read_yaml(path: str | Path, kind: str, error: type[Exception]) -> Any:
    """The parsed content of ``path``; ``error(f"{kind} {path}: ...")`` if it cannot be read or parsed."""
    path = Path(path)
    text = read_text(path, kind, error)
    try:
        return yaml.load(text, Loader=getattr(yaml, "CSafeLoader", yaml.SafeLoader))
    except yaml.YAMLError as exc:
        line = getattr(getattr(exc, "problem_mark", None), "line", None)
        at = f" (line {line + 1})" if line is not None else ""
        raise error(f"{kind} {path}: not valid YAML{at}") from None
