"""Options shared by several commands, defined once: the parameter file and its overrides, the
firmware and its sketch, the seed (the options of ``amr-twin run``: :mod:`amr_twin.cli.run_options`;
``--live``: :mod:`amr_twin.cli.live_options`; ``--ros1``: :mod:`amr_twin.cli.ros1_options`).
"""

from __future__ import annotations

from pathlib import Path
from typing import Callable, Optional

import typer

from amr_twin.controllers.firmware import FIRMWARES

ConfigOpt = typer.Option(None, "--config", help="Parameter file (default models/amr/amr.yaml).")
ParamsOpt = typer.Option(
    None, "--params", help="Second YAML overriding values of the parameter file."
)
SetOpt = typer.Option(None, "--set", help="Override one value: key=value (repeatable).")


def firmware_option(default: str = "faithful") -> typer.models.OptionInfo:
    """``--firmware``: its choices are the firmware factory's
    (:data:`~amr_twin.controllers.firmware.FIRMWARES`)."""
    return typer.Option(
        default,
        "--firmware",
        help=f"Arduino firmware: {FIRMWARES.choices()}; default {default} "
        "(firmware.md in docs/explanation/; avr: the sketch compiled with avr-gcc on an "
        "emulated ATmega2560).",
    )


def sketch_option() -> typer.models.OptionInfo:
    """``--sketch DIR``: the sketch of ``--firmware avr``."""
    return typer.Option(
        None,
        "--sketch",
        metavar="DIR",
        help="With --firmware avr: your Arduino sketch folder "
        "(DIR/DIR.ino) instead of controllers/arduino/motor_control.",
    )


def checked_firmware(firmware: str, sketch: Optional[Path], fail: Callable[[str], None]) -> str:
    """``--firmware`` and ``--sketch`` as the firmware string (``avr:DIR`` with a sketch); for avr
    the toolchain is checked and the sketch built now. A refusal is one line (``fail``)."""
    from amr_twin.controllers.firmware import check_avr, firmware_kind

    try:
        kind = firmware_kind(firmware, None if sketch is None else str(sketch))
        check_avr(kind)
    except ValueError as exc:
        fail(str(exc))
    return kind


SEED_LIMIT = 2**32
"""Seeds are whole numbers in [0, 2^32) (numpy's SeedSequence takes any non-negative one; a bound
keeps keys short)."""


def checked_seed(
    seed: Optional[int], fail: Callable[[str], None], option: str = "--seed"
) -> Optional[int]:
    """``--seed``: a whole number in [0, 2^32), or a one-line refusal (``fail``)."""
    if seed is not None and not 0 <= seed < SEED_LIMIT:
        fail(f"{option} {seed}: must be a whole number in [0, 2^32)")
    return seed
