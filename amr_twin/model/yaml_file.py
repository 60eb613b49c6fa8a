"""YAML input files (missions, routes) read with one-line errors that name the file.

A missing or unreadable file, or YAML that does not parse, raises the caller's
error class with ``"<kind> <path>: <reason>"`` (the line number of a syntax
error included), so the CLI can print it as is and exit non-zero.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import yaml


def read_yaml(path: str | Path, kind: str, error: type[Exception]) -> Any:
    """The parsed content of ``path``; ``error(f"{kind} {path}: ...")`` if it cannot be read or parsed."""
    path = Path(path)
    try:
        return yaml.load(path.read_text(), Loader=getattr(yaml, "CSafeLoader", yaml.SafeLoader))
    except OSError as exc:
        raise error(f"{kind} {path}: {exc.strerror or exc}") from None
    except yaml.YAMLError as exc:
        line = getattr(getattr(exc, "problem_mark", None), "line", None)
        at = f" (line {line + 1})" if line is not None else ""
        raise error(f"{kind} {path}: not valid YAML{at}") from None
