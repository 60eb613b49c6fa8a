"""The firmware factory: a firmware of a kind on the loop's clock (interface and parameters in
firmware_params).

Three firmwares implement :class:`Firmware`: ``faithful`` (a port of the thesis
listings 4.7-4.12, quirks included behind named switches) and ``improved`` run on
:class:`~amr_twin.controllers.arduino.ArduinoRuntime`, which emulates the Arduino
Mega 2560 on the shared :class:`~amr_twin.base.clock.VirtualClock`; ``avr`` is the
same firmware as an Arduino sketch (``controllers/arduino/motor_control``, or a
user's sketch folder) compiled with avr-gcc and run on an emulated ATmega2560
(:mod:`~amr_twin.controllers.avr`). A firmware that speaks rosserial on its own
UART says so from ``connect(bus, link)``; the loop then bridges neither
``wheel_Command`` nor ``wheelN_Vel`` itself.

Published speeds (``wheel0_Vel``, ``wheel1_Vel``) are RPM as a positive
magnitude: the SC output carries no direction, and the thesis firmware publishes
``60e6 / elapsed_us`` which is never negative.
"""

from __future__ import annotations

from typing import Protocol

from amr_twin.base.registry import Registry
from amr_twin.base.clock import VirtualClock

from amr_twin.controllers.firmware_params import (
    AvrParams,
    BoardParams,
    FaithfulParams,
    Firmware,
    ImprovedParams,
    Publish,
)

__all__ = [
    "FIRMWARES",
    "AvrParams",
    "BoardParams",
    "FaithfulParams",
    "Firmware",
    "FirmwareFactory",
    "ImprovedParams",
    "Publish",
    "check_avr",
    "firmware_identity",
    "firmware_kind",
    "make_firmware",
]


class FirmwareFactory(Protocol):
    """Builds a firmware on ``clock`` publishing through ``publish``: ``params`` (None: its
    defaults), ``edges_per_rev`` SC changes per wheel revolution, ``sketch`` the text after
    ``KIND:`` (None without)."""

    def __call__(
        self,
        clock: VirtualClock,
        publish: Publish,
        params,
        *,
        edges_per_rev: int,
        sketch: str | None,
    ) -> Firmware: ...


FIRMWARES: Registry[FirmwareFactory] = Registry("--firmware")
"""Firmware kinds by name (``faithful``, ``improved``, ``avr``); a third party registers its own
:class:`FirmwareFactory`. ``avr:DIR`` names a sketch folder for ``avr`` (see
:func:`firmware_kind`)."""


def firmware_kind(firmware: str, sketch: str | None = None) -> str:
    """The firmware string of ``--firmware KIND [--sketch DIR]``; ValueError naming the option.

    ``avr`` with a sketch becomes ``avr:/absolute/DIR``, a string that travels to worker
    processes and into reports like the other kinds.
    """
    FIRMWARES.get(firmware)
    if sketch is None:
        return firmware
    if firmware != "avr":
        raise ValueError(f"--sketch is used with --firmware avr only (got --firmware {firmware})")
    from pathlib import Path

    from amr_twin.controllers.avr_build import check_sketch

    check_sketch(Path(sketch))
    return f"avr:{Path(sketch).resolve()}"


def firmware_identity(firmware: str) -> str:
    """What identifies the firmware's behaviour: the kind, plus the sources' hash for ``avr``."""
    if not firmware.startswith("avr"):
        return firmware
    from amr_twin.controllers.avr_build import DEFAULT_SKETCH, source_hash

    sketch = firmware.partition(":")[2] or DEFAULT_SKETCH
    return f"{firmware}@{source_hash(sketch)}"


def check_avr(firmware: str, params: AvrParams | None = None) -> None:
    """For an ``avr`` firmware: the toolchain is there and the sketch builds as ``params`` run it
    (else ValueError, one line)."""
    if not firmware.startswith("avr"):
        return
    from amr_twin.controllers.avr_sketch import sketch_defines, topic_table
    from amr_twin.controllers.avr_build import (
        DEFAULT_SKETCH,
        SketchError,
        build_sketch,
        missing_tools,
    )

    problem = missing_tools()
    if problem:
        raise ValueError(f"--firmware avr: {problem}")
    try:
        topic_table(
            str(
                build_sketch(
                    firmware.partition(":")[2] or DEFAULT_SKETCH,
                    sketch_defines(params or AvrParams()),
                )
            )
        )
    except SketchError as exc:
        raise ValueError(f"--firmware {firmware}: {exc}") from None


SKETCH_EDGES_PER_REV = 90
"""SC changes per revolution the thesis sketch counts (``counter[index] == 90``,
motor_control.ino)."""


def make_firmware(
    kind: str,
    clock: VirtualClock,
    publish: Publish,
    params: FaithfulParams | ImprovedParams | AvrParams | None = None,
    *,
    edges_per_rev: int,
) -> Firmware:
    """Build a firmware of ``kind`` (a name of :data:`FIRMWARES`, or ``avr:SKETCH_DIR``) on
    ``clock`` (shared, us) publishing through ``publish(topic, rpm)`` (``wheel0_Vel`` /
    ``wheel1_Vel``); ``params`` defaults to the thesis values; ``edges_per_rev``: SC changes per
    wheel revolution (``wheel.sc_edges_per_rev``). ValueError (one line) for an unknown kind."""
    name, _, sketch = kind.partition(":")
    return FIRMWARES.get(name)(
        clock, publish, params, edges_per_rev=edges_per_rev, sketch=sketch or None
    )


@FIRMWARES.register("faithful")
def _faithful(
    clock: VirtualClock,
    publish: Publish,
    params: FaithfulParams | None,
    *,
    edges_per_rev: int,
    sketch: str | None,
) -> Firmware:
    """The port of the thesis listings 4.7-4.12, quirks included
    (:mod:`~amr_twin.controllers.faithful`)."""
    from amr_twin.controllers.faithful import FaithfulFirmware

    return FaithfulFirmware(clock, publish, edges_per_rev, params or FaithfulParams())


@FIRMWARES.register("improved")
def _improved(
    clock: VirtualClock,
    publish: Publish,
    params: ImprovedParams | None,
    *,
    edges_per_rev: int,
    sketch: str | None,
) -> Firmware:
    """The thesis firmware with its quirks fixed (:mod:`~amr_twin.controllers.improved`)."""
    from amr_twin.controllers.improved import ImprovedFirmware

    return ImprovedFirmware(clock, publish, edges_per_rev, params or ImprovedParams())


@FIRMWARES.register("avr")
def _avr(
    clock: VirtualClock,
    publish: Publish,
    params: AvrParams | None,
    *,
    edges_per_rev: int,
    sketch: str | None,
) -> Firmware:
    """The sketch (``sketch``, else the thesis' own) compiled with avr-gcc on an emulated
    ATmega2560; the thesis sketch has its count compiled in (:data:`SKETCH_EDGES_PER_REV`) and
    refuses any other."""
    from amr_twin.controllers.avr import AvrFirmware

    if sketch is None and edges_per_rev != SKETCH_EDGES_PER_REV:
        raise ValueError(
            f"--firmware avr: the thesis sketch counts {SKETCH_EDGES_PER_REV} SC changes per "
            f"revolution, the configured wheel has {edges_per_rev} (wheel.hall_pole_pairs)"
        )
    if params is None:
        params = AvrParams(sketch_dir=sketch)
    elif sketch is not None:
        from dataclasses import replace

        params = replace(params, sketch_dir=sketch)
    return AvrFirmware(clock, publish, params)
