"""Small C helpers of the loop, compiled at first use against the installed MuJoCo's headers.

A helper (a ``.c`` file next to its Python twin) is built with the system's C compiler
(``cc``) into the disk cache (:func:`amr_twin.base.disk_cache.cache_dir` ``native``), keyed
by the source, the MuJoCo version and the flags, written whole (temporary file, then
rename), and loaded with ctypes. It takes MuJoCo's ``mjModel*`` and ``mjData*`` (the
bindings' ``_address``) and reads and writes their arrays in place: one call instead of
some thirty Python reads of MjData per grid instant.

``-ffp-contract=off``: no fused multiply-adds, so the C helper and its Python twin round
every operation alike and give the same bits. Without a compiler, with the disk cache off
or with ``AMR_TWIN_NATIVE=0`` the Python twin runs (same results, slower);
:func:`native_status` says which and why.

Part of the physics layer (``PHYSICS_LAYER``): builds the C helpers that read and write MjData and
gives them its arrays' addresses.
"""

from __future__ import annotations

import ctypes
import hashlib
import os
import platform
import shutil
import subprocess
import sys
import tempfile
import warnings
from pathlib import Path

from amr_twin.base.disk_cache import cache_dir
from amr_twin.base.c_layout import LAYOUT_HEADER, layout_problem

PHYSICS_LAYER = True

NATIVE_ENV = "AMR_TWIN_NATIVE"
"""Environment variable: ``0`` runs the Python twins of the C helpers."""
FLAGS = ("-O2", "-std=c11", "-fPIC", "-shared", "-ffp-contract=off", "-fno-fast-math")
BUILD_FORMAT = 1
"""Part of every build's key: raise it when what a built helper means changes."""

_loaded: dict[str, ctypes.PyDLL | None] = {}
_why_not: dict[str, str] = {}


_char_at = ctypes.c_char.from_buffer


def address(array) -> int:
    """Address of the first byte of a C-contiguous numpy ``array``, to pass to a helper.

    Through the buffer protocol (about 0.8 us) rather than ``array.ctypes.data`` (about
    3 us: it builds a ctypes helper object each time); read-only arrays take the slow way.
    """
    try:
        return ctypes.addressof(_char_at(array))
    except (TypeError, ValueError, BufferError):
        return array.ctypes.data


def c_array(array, dtype):
    """``array`` as a C-contiguous numpy array of ``dtype`` for a helper: itself when it already is
    one (no call into ``numpy.ascontiguousarray``: these run at the sensors' rates)."""
    if array.dtype == dtype and array.flags.c_contiguous:
        return array
    import numpy as np

    return np.ascontiguousarray(array, dtype)


def mujoco_address(name: str) -> int:
    """Address of the symbol ``name`` (a function, or a variable such as ``mju_user_error``) in
    the libmujoco the bindings loaded (the same library: dlopen shares it)."""
    global _libmujoco
    if _libmujoco is None:
        import mujoco

        (lib,) = sorted(Path(mujoco.__file__).parent.glob("libmujoco.so*"))[:1] or [None]
        if lib is None:
            raise OSError("libmujoco.so not found next to the mujoco package")
        _libmujoco = ctypes.CDLL(str(lib))
    return ctypes.cast(getattr(_libmujoco, name), ctypes.c_void_p).value


_libmujoco = None


def _mujoco_include() -> tuple[Path, str]:
    import mujoco

    return Path(mujoco.__file__).parent / "include", mujoco.__version__


def load_helper(source: Path) -> ctypes.PyDLL | None:
    """The compiled helper of ``source`` (built if not cached), or None (see
    :func:`native_status`)."""
    name = str(source)
    if name in _loaded:
        return _loaded[name]
    lib, why = None, ""
    if os.environ.get(NATIVE_ENV, "1").strip() == "0":
        why = f"{NATIVE_ENV}=0"
    else:
        lib, why = _build_and_load(Path(source))
        why = layout_problem(source, lib) if lib is not None else why
        if (
            why and lib is not None
        ):  # its structs are not those of the Python side (amr_twin.base.c_layout)
            lib = None
            warnings.warn(f"{why}: the Python twin runs instead", RuntimeWarning, stacklevel=2)
    _loaded[name], _why_not[name] = lib, why
    return lib


def open_helper(source: Path, native: bool = True) -> tuple[ctypes.PyDLL | None, str]:
    """``(helper, engine)``: the built helper of ``source`` (None without one) and ``"C"`` or
    ``"Python (<why>)"``; ``native=False`` asks for the Python twin."""
    if not native:
        return None, "Python (native=False)"
    return load_helper(source), native_status(source)


def native_status(source: Path) -> str:
    """``"C"`` when the helper of ``source`` is in use, else ``"Python (<why>)"``."""
    lib = load_helper(source)
    return "C" if lib is not None else f"Python ({_why_not[str(source)]})"


def _build_and_load(source: Path) -> tuple[ctypes.PyDLL | None, str]:
    include, version = _mujoco_include()
    if not (include / "mujoco" / "mujoco.h").exists():
        return None, f"MuJoCo's headers not found in {include}"
    folder = cache_dir("native")
    if folder is None:
        return None, "disk cache off"
    try:
        text = source.read_bytes() + LAYOUT_HEADER.read_bytes()
    except OSError as exc:
        return None, f"{source.name}: {exc.strerror or exc}"
    machine = (
        f"{sys.platform} {platform.machine()} {sys.implementation.cache_tag}".encode()
    )  # a shared home
    key = hashlib.sha256(
        b"\0".join(
            [text, version.encode(), " ".join(FLAGS).encode(), machine, str(BUILD_FORMAT).encode()]
        )
    ).hexdigest()[:24]
    target = folder / f"{source.stem}-{key}.so"
    if not target.exists():
        compiler = shutil.which("cc") or shutil.which("gcc")
        if compiler is None:
            return None, "no C compiler (cc)"
        tmp = None
        try:
            folder.mkdir(parents=True, exist_ok=True)
            fd, tmp = tempfile.mkstemp(dir=folder, prefix=f".{target.name}.", suffix=".tmp")
            os.close(fd)
            command = [
                compiler,
                *FLAGS,
                "-I",
                str(include),
                "-I",
                str(LAYOUT_HEADER.parent),
                str(source),
                "-o",
                tmp,
                "-lm",
            ]
            out = subprocess.run(command, capture_output=True, text=True, timeout=120)
            if out.returncode != 0:
                first = (out.stderr.strip().splitlines() or ["failed"])[0]
                return None, f"{source.name} did not compile: {first}"
            os.replace(tmp, target)
            tmp = None
        except (OSError, subprocess.SubprocessError) as exc:
            return None, f"{source.name} could not be built: {exc}"
        finally:
            if tmp is not None:
                Path(tmp).unlink(missing_ok=True)
    try:
        return ctypes.PyDLL(
            str(target)
        ), ""  # PyDLL: the call holds the GIL, as its Python twin does
    except OSError as exc:
        target.unlink(missing_ok=True)  # the next process builds it again
        return None, f"{target.name} could not be loaded: {exc}"
