"""A parameter file read into its raw tree (values with units and sources), parsed once.

:func:`read_tree` keeps each file version's tree in the process; :func:`read_yaml` keeps
parsed trees on disk too (:mod:`amr_twin.base.disk_cache`, keyed by the file's bytes), so
that a command's start-up imports PyYAML and parses the file only when it changed. Errors
are :class:`~amr_twin.model.config_leaves.ConfigError` with one line naming the file.
"""

from __future__ import annotations

import hashlib
import marshal
import pickle
from pathlib import Path

from amr_twin.model.config_leaves import ConfigError
from amr_twin.base.disk_cache import cache_dir, read_entry, store
from amr_twin.model.paths import MODEL_DIR

DEFAULT_CONFIG = MODEL_DIR / "amr.yaml"
"""The robot's parameter file."""

TREE_CACHE_FORMAT = 1
"""Part of every parsed-tree cache key: raise it when what a cached tree means changes."""


MAX_PARAMETER_FILE_BYTES = 16 * 1024 * 1024
"""Largest parameter file read, bytes (amr.yaml is ~40 kB): a device or a huge file is refused, not
read."""


def _read_text(path: Path) -> bytes:
    if (
        path.exists() and not path.is_dir() and not path.is_file()
    ):  # opening a pipe would wait for a writer
        raise ConfigError(
            f"{path}: not a regular file (a device or a pipe), not a parameter file (YAML)"
        )
    try:
        with open(path, "rb") as fh:
            raw = fh.read(MAX_PARAMETER_FILE_BYTES + 1)
        if len(raw) > MAX_PARAMETER_FILE_BYTES:
            raise ConfigError(
                f"{path}: larger than {MAX_PARAMETER_FILE_BYTES // 1024 // 1024} MB, not a "
                f"parameter "
                "file"
            )
        return raw
    except FileNotFoundError:
        raise ConfigError(f"{path}: no such parameter file") from None
    except IsADirectoryError:
        raise ConfigError(f"{path}: is a folder, not a parameter file (YAML)") from None
    except OSError as exc:
        raise ConfigError(f"{path}: cannot be read ({exc.strerror or exc})") from None


def _parse_yaml(path: Path, raw: bytes) -> dict:
    import yaml  # ~25 ms of start-up: only when the file is not in the cache

    try:
        data = yaml.load(raw.decode("utf-8"), Loader=getattr(yaml, "CSafeLoader", yaml.SafeLoader))
    except UnicodeDecodeError:
        raise ConfigError(f"{path}: not a text file (a YAML parameter file is expected)") from None
    except yaml.YAMLError as exc:
        raise ConfigError(f"{path}: not valid YAML ({str(exc).splitlines()[0]})") from None
    if not isinstance(data, dict):
        raise ConfigError(f"{path}: expected a mapping at the top level")
    return data


def read_yaml(path: Path) -> dict:
    """The parsed parameter file; from the disk cache (:mod:`amr_twin.base.disk_cache`, keyed by
    the file's bytes) when this content was parsed before: parsing and importing PyYAML are
    ~35 ms of a 1 s run's start-up. Entries are ``marshal`` data (plain values, nothing to run)."""
    raw = _read_text(path)
    folder = cache_dir("yaml")
    key = hashlib.sha256(b"tree %d\0" % TREE_CACHE_FORMAT + raw).hexdigest()[:32]
    entry = folder / f"{key}.marshal" if folder is not None else None
    cached = read_entry(entry)
    if cached is not None:
        try:
            data = marshal.loads(cached)
        except (EOFError, ValueError, TypeError):
            data = None
        if isinstance(data, dict):
            return data
    data = _parse_yaml(path, raw)
    if entry is not None:
        try:
            blob = marshal.dumps(data)
        except ValueError:  # a value marshal cannot hold (a YAML date): not cached
            blob = None
        if blob is not None:
            store(entry, blob)
    return data


_trees: dict[tuple[str, int, int], bytes] = {}


def read_tree(path: str | Path | None = None) -> dict:
    """The raw YAML tree of a parameter file (with units and sources), a fresh copy.

    Parsed once per file version (path, modification time, size) in a process: a sweep
    loads the parameter file once per point (~13 ms of YAML, ~0.2 ms from the memo).
    """
    path = Path(path) if path is not None else DEFAULT_CONFIG
    try:
        st = path.stat()
        key = (str(path.resolve()), st.st_mtime_ns, st.st_size)
    except OSError:
        key = None  # read_yaml names the problem
    if key in _trees:
        return pickle.loads(_trees[key])
    tree = read_yaml(path)
    if key is not None:
        _trees[key] = pickle.dumps(tree)
    return tree
