"""Build an Arduino sketch for the Mega 2560 with avr-gcc against Debian's Arduino AVR core.

What the Arduino IDE does, reduced to what the twin needs: the sketch's ``.ino`` files are
joined into one C++ file (the main one, named like the folder, first; then the others in
alphabetical order) after ``#include <Arduino.h>``, with ``#line`` marks so that compiler
messages name the ``.ino`` lines; the sketch's ``.c``/``.cpp``/``.S`` files, the libraries
in ``controllers/arduino/libraries`` and the core's bundled libraries are compiled and
linked with the core. Unlike the IDE, no function prototypes are generated: a sketch must
declare a function before it uses it.

Flags are the IDE's for the Mega (``platform.txt``, ``boards.txt``) without ``-flto``.
``WString.cpp`` is compiled with ``-DDECIMAL_DIG=9``: avr-libc's ``float.h`` lacks it and the
value is the one of a 32-bit double.

The core and libraries are compiled once per toolchain and cached as archives; the ELF is
cached per hash of everything that goes into it (sources, flags, compiler version), in
``$XDG_CACHE_HOME/amr-twin/avr`` (default ``~/.cache``). A build writes into a temporary
folder and renames it, so parallel workers may build the same sketch.
"""

from __future__ import annotations

import hashlib
import os
import re
import shutil
import subprocess
import tempfile
from pathlib import Path

ARDUINO_AVR = Path("/usr/share/arduino/hardware/arduino/avr")
"""Debian's arduino-core-avr: cores/arduino, variants/mega, libraries."""

PROJECT_ARDUINO = Path(__file__).resolve().parent / "arduino"
DEFAULT_SKETCH = PROJECT_ARDUINO / "motor_control"
"""The thesis firmware reconstructed as a sketch."""

LIBRARIES = PROJECT_ARDUINO / "libraries"
"""The project's Arduino libraries (ros_lib, TimerOne)."""

DEBIAN_PACKAGES = ("gcc-avr", "avr-libc", "arduino-core-avr", "simavr", "libsimavr-dev", "gcc")
"""What the AVR path needs (``apt-get install``)."""

MCU = "atmega2560"
F_CPU_HZ = 16_000_000
COMMON = [
    f"-mmcu={MCU}",
    f"-DF_CPU={F_CPU_HZ}L",
    "-DARDUINO=10807",
    "-DARDUINO_AVR_MEGA2560",
    "-DARDUINO_ARCH_AVR",
    "-Os",
    "-g",
    "-ffunction-sections",
    "-fdata-sections",
]
C_FLAGS = ["-std=gnu11"]
CXX_FLAGS = [
    "-std=gnu++11",
    "-fpermissive",
    "-fno-exceptions",
    "-fno-threadsafe-statics",
    "-Wno-error=narrowing",
]
LINK_FLAGS = [f"-mmcu={MCU}", "-Os", "-Wl,--gc-sections"]
SOURCE_SUFFIXES = (".c", ".cpp", ".S")


class SketchError(ValueError):
    """A sketch folder that cannot be built (missing, no .ino, a compiler error)."""


def missing_tools() -> str | None:
    """Why the AVR path cannot run here, or None when everything it needs is installed."""
    missing = [
        tool
        for tool in ("avr-gcc", "avr-g++", "avr-ar", "avr-nm", "cc")
        if shutil.which(tool) is None
    ]
    if not (ARDUINO_AVR / "cores" / "arduino" / "Arduino.h").exists():
        missing.append(f"{ARDUINO_AVR}/cores/arduino")
    if not Path("/usr/include/simavr/sim_avr.h").exists():
        missing.append("/usr/include/simavr/sim_avr.h")
    if not missing:
        return None
    return f"the AVR firmware needs {', '.join(missing)}: apt-get install " + " ".join(
        DEBIAN_PACKAGES
    )


def cache_dir() -> Path:
    """Where built cores, libraries, ELFs and the simavr bridge are kept."""
    base = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(base) / "amr-twin" / "avr"


def check_sketch(sketch_dir: Path) -> Path:
    """The main ``.ino`` of ``sketch_dir``; :class:`SketchError` if there is none."""
    sketch_dir = Path(sketch_dir)
    if not sketch_dir.is_dir():
        raise SketchError(f"--sketch {sketch_dir}: not a folder")
    main = sketch_dir / f"{sketch_dir.resolve().name}.ino"
    if not main.is_file():
        inos = sorted(sketch_dir.glob("*.ino"))
        if len(inos) != 1:
            raise SketchError(
                f"--sketch {sketch_dir}: needs {main.name} (an Arduino sketch folder holds "
                "FOLDER/FOLDER.ino)"
            )
        main = inos[0]
    return main


def _compiler_id() -> str:
    out = subprocess.run(
        ["avr-gcc", "--version"], capture_output=True, text=True, check=True
    ).stdout
    return out.splitlines()[0]


def _sources(folder: Path, recursive: bool) -> list[Path]:
    files = folder.rglob("*") if recursive else folder.glob("*")
    return sorted(p for p in files if p.is_file() and p.suffix in SOURCE_SUFFIXES)


def _hash_files(h, files: list[Path], root: Path) -> None:
    for f in files:
        h.update(str(f.relative_to(root)).encode() + b"\0" + f.read_bytes() + b"\0")


def _tree_files(folder: Path) -> list[Path]:
    return sorted(
        p
        for p in folder.rglob("*")
        if p.is_file() and p.suffix in SOURCE_SUFFIXES + (".h", ".hpp", ".ino")
    )


def _compile(src: Path, obj: Path, includes: list[Path], extra: list[str] = ()) -> None:
    cmd = (
        ["avr-g++", *COMMON, *CXX_FLAGS] if src.suffix == ".cpp" else ["avr-gcc", *COMMON, *C_FLAGS]
    )
    if src.suffix == ".S":
        cmd = ["avr-gcc", *COMMON, "-x", "assembler-with-cpp"]
    cmd += [*extra, *(f"-I{i}" for i in includes), "-c", str(src), "-o", str(obj)]
    run = subprocess.run(cmd, capture_output=True, text=True)
    if run.returncode != 0:
        raise SketchError(_first_error(run.stderr, src))


def _first_error(stderr: str, src: Path) -> str:
    lines = [ln for ln in stderr.splitlines() if ": error:" in ln or ": fatal error:" in ln]
    line = (lines or stderr.strip().splitlines() or [f"{src}: compiler failed"])[0]
    if "was not declared in this scope" in line:
        line += " (declare functions before use: the build generates no prototypes)"
    return line


def _archive(objs: list[Path], target: Path) -> None:
    subprocess.run(["avr-ar", "rcs", str(target), *map(str, objs)], check=True, capture_output=True)


def _publish(tmp: Path, final: Path) -> None:
    """Rename the finished ``tmp`` folder to ``final`` (another process may have won)."""
    try:
        os.replace(tmp, final)
    except OSError:
        shutil.rmtree(tmp, ignore_errors=True)
        if not final.exists():
            raise


def _core_includes() -> list[Path]:
    return [ARDUINO_AVR / "cores" / "arduino", ARDUINO_AVR / "variants" / "mega"]


def _library_dirs() -> list[Path]:
    """Include folders of the project's and the core's libraries (``src`` when present)."""
    dirs = []
    for root in (LIBRARIES, ARDUINO_AVR / "libraries"):
        for lib in sorted(p for p in root.glob("*") if p.is_dir()):
            dirs.append(lib / "src" if (lib / "src").is_dir() else lib)
    return dirs


def _build_archive(
    name: str, sources: list[Path], includes: list[Path], key: str, skip_failures: bool = False
) -> Path:
    final = cache_dir() / f"{name}-{key}"
    target = final / f"{name}.a"
    if target.exists():
        return target
    cache_dir().mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(prefix=f"{name}-", dir=cache_dir()))
    objs = []
    for i, src in enumerate(sources):
        obj = tmp / f"{i:03d}_{src.name}.o"
        extra = ["-DDECIMAL_DIG=9"] if src.name == "WString.cpp" else []
        try:
            _compile(src, obj, includes, extra)
        except SketchError:
            if not skip_failures:
                raise
            continue
        objs.append(obj)
    _archive(objs, tmp / f"{name}.a")
    _publish(tmp, final)
    return target


def build_sketch(sketch_dir: Path = DEFAULT_SKETCH, defines: tuple[str, ...] = ()) -> Path:
    """Compile and link ``sketch_dir`` for the Mega; return the cached ELF's path.

    ``defines``: preprocessor names defined for the sketch's own files (``-DNAME``).

    Raises :class:`SketchError` (with the compiler's first error line) or ``RuntimeError``
    when the toolchain is missing (:func:`missing_tools`).
    """
    problem = missing_tools()
    if problem:
        raise RuntimeError(problem)
    sketch_dir = Path(sketch_dir).resolve()
    main = check_sketch(sketch_dir)
    toolchain = hashlib.sha256(
        (_compiler_id() + "|" + " ".join(COMMON + C_FLAGS + CXX_FLAGS)).encode()
    )
    core_src = _sources(ARDUINO_AVR / "cores" / "arduino", recursive=False)
    _hash_files(toolchain, core_src, ARDUINO_AVR)
    core_key = toolchain.hexdigest()[:16]
    core = _build_archive("core", core_src, _core_includes(), core_key)

    lib_dirs = _library_dirs()
    lib_src = [s for d in lib_dirs for s in _sources(d, recursive=True)]
    lib_hash = hashlib.sha256(core_key.encode())
    for root in (LIBRARIES, ARDUINO_AVR / "libraries"):
        _hash_files(lib_hash, _tree_files(root), root)
    libs = _build_archive(
        "libs", lib_src, _core_includes() + lib_dirs, lib_hash.hexdigest()[:16], skip_failures=True
    )

    flags = [f"-D{d}" for d in defines]
    h = hashlib.sha256((lib_hash.hexdigest() + " ".join(LINK_FLAGS + flags)).encode())
    _hash_files(h, _tree_files(sketch_dir), sketch_dir)
    final = cache_dir() / f"sketch-{sketch_dir.name}-{h.hexdigest()[:16]}"
    elf = final / f"{sketch_dir.name}.elf"
    if elf.exists():
        return elf
    tmp = Path(tempfile.mkdtemp(prefix="sketch-", dir=cache_dir()))
    try:
        includes = [sketch_dir] + _core_includes() + lib_dirs
        joined = tmp / f"{sketch_dir.name}.ino.cpp"
        inos = [main] + sorted(p for p in sketch_dir.glob("*.ino") if p != main)
        parts = ["#include <Arduino.h>\n"]
        for ino in inos:
            parts.append(f'#line 1 "{ino}"\n{ino.read_text()}\n')
        joined.write_text("".join(parts))
        objs = []
        for i, src in enumerate([joined] + _sources(sketch_dir, recursive=False)):
            obj = tmp / f"{i:03d}_{src.name}.o"
            _compile(src, obj, includes, flags)
            objs.append(obj)
        link = subprocess.run(
            [
                "avr-gcc",
                *LINK_FLAGS,
                "-o",
                str(tmp / elf.name),
                *map(str, objs),
                str(libs),
                str(core),
                "-lm",
            ],
            capture_output=True,
            text=True,
        )
        if link.returncode != 0:
            raise SketchError(_first_link_error(link.stderr))
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise
    _publish(tmp, final)
    return elf


def _first_link_error(stderr: str) -> str:
    lines = [ln for ln in stderr.splitlines() if "undefined reference" in ln or "error" in ln]
    line = (lines or stderr.strip().splitlines() or ["link failed"])[0]
    return re.sub(r"\S*/tmp\S*/", "", line)


def source_hash(sketch_dir: Path = DEFAULT_SKETCH) -> str:
    """Hash of a sketch's sources and the project's libraries (identifies what runs)."""
    h = hashlib.sha256()
    for root in (Path(sketch_dir).resolve(), LIBRARIES):
        _hash_files(h, _tree_files(root), root)
    return h.hexdigest()[:16]
