"""What every command group shares: the one-line failure, the parameter file from the options, the
error guard, the garbage collector's start-up settings.

Each command module (main, run, experiment, fusion, menu) imports these from here, so
that no command module imports another.
"""

from __future__ import annotations

import gc
import math
from pathlib import Path
from typing import Optional

import typer

START_UP_GC_THRESHOLDS = (100_000, 50, 100)
"""Garbage-collector thresholds while a command starts (Python's default: 700, 10, 10)."""
_RUNTIME_GC_THRESHOLDS = gc.get_threshold()


def start_up() -> None:
    """A command starts: rarer collections while the imports build about a million objects
    (the default thresholds scan them over and over: ~40 ms of a 1 s run)."""
    gc.set_threshold(*START_UP_GC_THRESHOLDS)


def started() -> None:
    """The command's imports are done (its parameters are loaded): the start-up objects are frozen
    out of every later collection and the usual thresholds come back, so that a long sweep frees
    each point's twin as before (with the start-up thresholds kept, 120 points grew from 78 to 156
    MB)."""
    gc.freeze()
    gc.set_threshold(*_RUNTIME_GC_THRESHOLDS)


def fail(message: str, code: int = 2) -> None:
    """Print a one-line error and exit non-zero."""
    typer.echo(f"error: {message}", err=True)
    raise typer.Exit(code)


def checked(check, *args):
    """``check(*args)``'s value; its ValueError (an experiment spec's refusal) as :func:`fail`'s one
    line."""
    try:
        return check(*args)
    except ValueError as exc:
        fail(str(exc))


def _start_pose(
    text: Optional[str], option: str = "--start", hint: str = ", e.g. -7.5,0,0"
) -> Optional[tuple[float, float, float]]:
    """``X_M,Y_M,YAW_DEG`` to ``(x_m, y_m, yaw_rad)``; None: the world's; a one-line error naming
    ``option`` otherwise (``hint`` after what is expected)."""
    if text is None:
        return None
    try:
        x_m, y_m, yaw_deg = (float(v) for v in text.split(","))
    except ValueError:
        fail(f"{option} {text!r}: expected X_M,Y_M,YAW_DEG{hint}")
    if not all(math.isfinite(v) and abs(v) <= 1e4 for v in (x_m, y_m, yaw_deg)):
        fail(f"{option} {text!r}: each value must be finite and within +-10000")
    return x_m, y_m, math.radians(yaw_deg)


OPTION_OF = {
    "payload.mass_kg": "--payload-kg",
    "payload.xy_m": "--payload-xy",
    "navigation.navigator.xy_tolerance_m": "--xy-tolerance-m",
    "navigation.costmap.inflation_radius_m": "--inflation-radius-m",
}
"""The parameter each command option sets (the ``extra`` of :func:`_config`)."""


def _shown(value) -> str:
    return ",".join(f"{v:g}" for v in value) if isinstance(value, (list, tuple)) else f"{value:g}"


def _check_set_against_options(sets: list[str], extra: dict) -> None:
    """A ``--set`` of a parameter that a command option (:data:`OPTION_OF`) also sets, to another
    value: one line naming both (the option won, the ``--set`` was ignored); the same value is
    accepted."""
    from amr_twin.model.config_overrides import parse_assignment

    for text in sets:
        key, value = parse_assignment(text)
        if key not in extra or key not in OPTION_OF:
            continue
        given = extra[key]
        try:  # a value of the wrong kind is named by the parameter's own check
            same = (
                [float(v) for v in value] == [float(v) for v in given]
                if isinstance(value, (list, tuple))
                else float(value) == float(given)
            )
        except (TypeError, ValueError):
            continue
        if not same:
            fail(
                f"--set {text!r} and {OPTION_OF[key]} {_shown(given)} both set {key}, to "
                f"different values: "
                "give one of them"
            )


def _config(
    config: Optional[Path],
    params: Optional[Path],
    sets: Optional[list[str]],
    extra: dict | None = None,
):
    from amr_twin.model.config import (
        ConfigError,
        load_config,
    )  # pydantic and numpy: not on the path of --help

    try:
        _check_set_against_options(sets or [], extra or {})
        cfg = load_config(config, override_file=params, sets=sets or [], overrides=extra)
        started()
        return cfg
    except ConfigError as exc:
        text = str(exc)
        for option, path in (("--params", params), ("--config", config)):
            if path is not None and text.startswith(f"{path}:"):
                text = f"{option} {text}"
                break
        for key, value in (extra or {}).items():
            if text.startswith(f"{key}:") and key in OPTION_OF:
                text = f"{OPTION_OF[key]} {_shown(value)}: {text}"
        fail(text)


def _guard(func):
    """Turn the twin's own errors into one-line messages.

    Bad input found while building (a world file, a start pose): exit 2. The
    simulation diverged: exit 3. A file could not be written (disk full, read-only):
    exit 1, naming the file.
    """
    from amr_twin.base.atomic_file import WriteError
    from amr_twin.model.build import BuildError
    from amr_twin.model.config import ConfigError
    from amr_twin.sim.physics import DivergenceError

    try:
        return func()
    except (ConfigError, BuildError, ValueError) as exc:
        fail(str(exc).splitlines()[0] if str(exc) else type(exc).__name__)
    except DivergenceError as exc:
        fail(str(exc), code=3)
    except WriteError as exc:
        fail(f"cannot write {exc.filename}: {exc.strerror}", code=1)
    except (
        MemoryError
    ):  # a traceback of 116 lines under ulimit -v; the outputs are written whole or not at all
        from amr_twin.sim.bounds import address_space_mb

        limit = address_space_mb()
        fail(
            "out of memory"
            + (f" (the limit, ulimit -v, is {limit / 1024:.1f} GB)" if limit else "")
            + "; nothing written: ask for less (a shorter run, no recording, fewer --jobs)",
            code=1,
        )
    except OSError as exc:
        fail(f"{exc.filename + ': ' if exc.filename else ''}{exc.strerror or exc}", code=1)
