"""YAML input files (missions, routes, maps) read with one-line errors that name the file.

A missing or unreadable file, a folder or a device, a file over :data:`MAX_YAML_BYTES`, bytes that
are not UTF-8 text, or YAML that does not parse, raises the caller's error class with
``"<kind> <path>: <reason>"`` (the line number of a syntax error included), so the CLI can print it
as is and exit non-zero. Nothing is read past the size bound (``/dev/zero`` is refused, not read; a
pipe is refused, not waited on). :func:`read_bytes` does the same for binary inputs (a map's image).

Numbers are read as YAML 1.2 reads them: ``1e-9`` and ``1e308`` are numbers (PyYAML's YAML 1.1 makes
them words, and a map's ``resolution: 1e-9`` was refused as "not a finite number").
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

import yaml


class Loader(getattr(yaml, "CSafeLoader", yaml.SafeLoader)):  # type: ignore[misc]
    """PyYAML's safe loader, with exponent numbers without a dot (``1e-9``) read as floats."""


Loader.add_implicit_resolver(
    "tag:yaml.org,2002:float",
    re.compile(r"^[-+]?[0-9][0-9_]*(?:\.[0-9_]*)?[eE][-+]?[0-9]+$"),
    list("-+0123456789"),
)


MAX_YAML_BYTES = 16 * 1024 * 1024
"""Largest YAML input read, bytes (a mission of a million steps is ~40 MB of YAML and a long
parse)."""


def read_bytes(
    path: str | Path, kind: str, error: type[Exception], limit: int = MAX_YAML_BYTES
) -> bytes:
    """The bytes of a regular file of at most ``limit`` bytes; ``error(f"{kind} {path}: ...")``
    otherwise (``f"{path}: ..."`` with no ``kind``)."""
    path = Path(path)
    where = f"{kind} {path}" if kind else str(path)
    if path.is_dir():
        raise error(f"{where}: is a folder, not a file")
    if (
        path.exists() and not path.is_file()
    ):  # checked before opening: opening a pipe waits for a writer
        raise error(f"{where}: not a regular file (a device or a pipe)")
    try:
        with open(path, "rb") as fh:
            data = fh.read(limit + 1)
    except OSError as exc:
        raise error(f"{where}: {exc.strerror or exc}") from None
    if len(data) > limit:
        raise error(f"{where}: larger than {limit // 1024 // 1024} MB")
    return data


def read_text(
    path: str | Path, kind: str, error: type[Exception], limit: int = MAX_YAML_BYTES
) -> str:
    """The UTF-8 text of a regular file of at most ``limit`` bytes (:func:`read_bytes`)."""
    data = read_bytes(path, kind, error, limit)
    where = f"{kind} {path}" if kind else str(path)
    try:
        return data.decode()
    except UnicodeDecodeError as exc:
        raise error(f"{where}: not a text file (byte {exc.start} is not UTF-8)") from None


def read_yaml(path: str | Path, kind: str, error: type[Exception]) -> Any:
    """The parsed content of ``path``; ``error(f"{kind} {path}: ...")`` if it cannot be read or
    parsed."""
    path = Path(path)
    text = read_text(path, kind, error)
    try:
        return yaml.load(text, Loader=Loader)
    except yaml.YAMLError as exc:
        line = getattr(getattr(exc, "problem_mark", None), "line", None)
        at = f" (line {line + 1})" if line is not None else ""
        raise error(f"{kind} {path}: not valid YAML{at}") from None
