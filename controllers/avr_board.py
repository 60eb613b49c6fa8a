"""An emulated ATmega2560 (libsimavr) running an ELF: pins, UART and time in CPU cycles.

The C side is ``controllers/arduino/cosim/avr_cosim.c``, compiled once with the host's ``cc``
against libsimavr and cached next to the ELFs (:func:`amr_twin.controllers.avr_build.cache_dir`),
then loaded with ctypes. :class:`AvrBoard` advances the core with :meth:`AvrBoard.run_to`
(cycle-accurate, instruction by instruction, in C); inputs queued with their cycle (pin edges,
UART bytes) are applied by simavr at that cycle.

Arduino pin numbers are mapped to ports, bits and timer channels with the Mega's
``variants/mega/pins_arduino.h`` of Debian's Arduino core (parsed, not copied).
"""

from __future__ import annotations

import ctypes
import hashlib
import re
import subprocess
import tempfile
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

from amr_twin.controllers.avr_build import ARDUINO_AVR, F_CPU_HZ, MCU, cache_dir, missing_tools

BRIDGE_SOURCE = Path(__file__).resolve().parent / "arduino" / "cosim" / "avr_cosim.c"

PORT_ADDR = {
    "A": 0x22,
    "B": 0x25,
    "C": 0x28,
    "D": 0x2B,
    "E": 0x2E,
    "F": 0x31,
    "G": 0x34,
    "H": 0x102,
    "J": 0x105,
    "K": 0x108,
    "L": 0x10B,
}
"""Data-space address of PORTx on the ATmega2560 (PINx = PORTx - 2, DDRx = PORTx - 1)."""

TIMER_TCCRA = {0: 0x44, 1: 0x80, 2: 0xB0, 3: 0x90, 4: 0xA0, 5: 0x120}
"""TCCRnA address per timer."""

OCR_ADDR = {
    "0A": 0x47,
    "0B": 0x48,
    "1A": 0x88,
    "1B": 0x8A,
    "1C": 0x8C,
    "2A": 0xB3,
    "2B": 0xB4,
    "3A": 0x98,
    "3B": 0x9A,
    "3C": 0x9C,
    "4A": 0xA8,
    "4B": 0xAA,
    "4C": 0xAC,
    "5A": 0x128,
    "5B": 0x12A,
    "5C": 0x12C,
}
"""OCRnx (low byte) address per timer channel."""

COM_BIT = {"A": 7, "B": 5, "C": 3}
"""COMnx1 bit in TCCRnA."""

CPU_DONE, CPU_CRASHED = 6, 7
"""simavr states that end a run (``cpu_Done``, ``cpu_Crashed`` in sim_avr.h)."""


@dataclass(frozen=True)
class PinInfo:
    """Where an Arduino pin lives: port letter, bit, and PWM timer channel (e.g. ``"4A"``) or
    None."""

    port: str
    bit: int
    timer: str | None


@lru_cache(maxsize=1)
def mega_pins() -> dict[int, PinInfo]:
    """Arduino pin number -> :class:`PinInfo`, from the Mega variant's pins_arduino.h."""
    text = (ARDUINO_AVR / "variants" / "mega" / "pins_arduino.h").read_text()

    def table(name: str) -> list[str]:
        body = re.search(name + r"\[\]\s*=\s*\{(.*?)\n\};", text, re.S).group(1)
        return re.findall(r"^\s*([A-Z_]+[0-9A-Z_]*|_BV\(\s*\d+\s*\))\s*,", body, re.M)

    ports, masks, timers = (
        table(n)
        for n in (
            "digital_pin_to_port_PGM",
            "digital_pin_to_bit_mask_PGM",
            "digital_pin_to_timer_PGM",
        )
    )
    pins = {}
    for pin, (port, mask, timer) in enumerate(zip(ports, masks, timers)):
        bit = int(re.search(r"\d+", mask).group())
        channel = None if timer == "NOT_ON_TIMER" else timer.removeprefix("TIMER")
        pins[pin] = PinInfo(port.removeprefix("P"), bit, channel)
    return pins


def symbol_address(elf: Path, name: str) -> int:
    """Address (bytes) of the function ``name`` in ``elf`` (avr-nm)."""
    out = subprocess.run(["avr-nm", str(elf)], capture_output=True, text=True, check=True).stdout
    for line in out.splitlines():
        parts = line.split()
        if len(parts) == 3 and parts[2] == name and parts[1] in "Tt":
            return int(parts[0], 16)
    raise BoardError(f"{elf}: no function {name}")


def _bridge_path() -> Path:
    digest = hashlib.sha256(BRIDGE_SOURCE.read_bytes()).hexdigest()[:16]
    return cache_dir() / f"avr_cosim-{digest}.so"


@lru_cache(maxsize=1)
def _library() -> ctypes.CDLL:
    problem = missing_tools()
    if problem:
        raise RuntimeError(problem)
    path = _bridge_path()
    if not path.exists():
        path.parent.mkdir(parents=True, exist_ok=True)
        with tempfile.NamedTemporaryFile(dir=path.parent, suffix=".so", delete=False) as tmp:
            pass
        run = subprocess.run(
            ["cc", "-O2", "-shared", "-fPIC", "-o", tmp.name, str(BRIDGE_SOURCE), "-lsimavr"],
            capture_output=True,
            text=True,
        )
        if run.returncode != 0:
            Path(tmp.name).unlink(missing_ok=True)
            raise RuntimeError(
                f"building {BRIDGE_SOURCE.name} failed: {run.stderr.strip().splitlines()[0]}"
            )
        Path(tmp.name).replace(path)
    lib = ctypes.CDLL(str(path))
    p, u8, u16, u32, u64 = (
        ctypes.c_void_p,
        ctypes.c_uint8,
        ctypes.c_uint16,
        ctypes.c_uint32,
        ctypes.c_uint64,
    )
    sig = {
        "cosim_open": (p, [ctypes.c_char_p, ctypes.c_char_p, u32, ctypes.c_char_p, ctypes.c_int]),
        "cosim_close": (None, [p]),
        "cosim_add_output": (ctypes.c_int, [p, u16, u8, u16, u8, u16]),
        "cosim_add_input": (ctypes.c_int, [p, ctypes.c_char, u8, u8]),
        "cosim_queue_edge": (ctypes.c_int, [p, u64, ctypes.c_int]),
        "cosim_queue_rx": (ctypes.c_int, [p, u64, ctypes.c_char_p, ctypes.c_int, u32]),
        "cosim_run": (ctypes.c_int, [p, u64]),
        "cosim_run_to_pc": (ctypes.c_int, [p, u32, u64]),
        "cosim_run_until_change": (ctypes.c_int, [p, u64]),
        "cosim_cycle": (u64, [p]),
        "cosim_outputs": (u64, [p]),
        "cosim_peek": (u8, [p, u16]),
        "cosim_tx_take": (ctypes.c_int, [p, ctypes.POINTER(u64), ctypes.POINTER(u8), ctypes.c_int]),
        "cosim_tx_pending": (ctypes.c_int, [p]),
        "cosim_last_log": (ctypes.c_char_p, []),
    }
    for name, (res, args) in sig.items():
        fn = getattr(lib, name)
        fn.restype, fn.argtypes = res, args
    return lib


class BoardError(RuntimeError):
    """The emulated board stopped (the firmware crashed or slept with interrupts off)."""


class AvrBoard:
    """One ATmega2560 at 16 MHz running ``elf``.

    Parameters
    ----------
    elf : path of the firmware.
    outputs : Arduino pins read by :meth:`outputs` (at most 8), in order.
    inputs : ``{pin: initial level}`` of the digital inputs driven by :meth:`queue_edge`.
    """

    def __init__(self, elf: Path, outputs: list[int], inputs: dict[int, int]):
        self._lib = lib = _library()
        err = ctypes.create_string_buffer(256)
        self._s = lib.cosim_open(str(elf).encode(), MCU.encode(), F_CPU_HZ, err, len(err))
        if not self._s:
            raise BoardError(err.value.decode())
        pins = mega_pins()
        if len(outputs) > 8:
            raise ValueError("at most 8 output pins")
        for pin in outputs:
            info = pins[pin]
            if info.timer is not None:
                timer, channel = int(info.timer[0]), info.timer[-1]
                tccr, com, ocr = (
                    TIMER_TCCRA[timer],
                    1 << COM_BIT.get(channel, 7),
                    OCR_ADDR[info.timer],
                )
            else:
                tccr = com = ocr = 0
            lib.cosim_add_output(self._s, PORT_ADDR[info.port], info.bit, tccr, com, ocr)
        self._inputs = {}
        for pin, level in inputs.items():
            info = pins[pin]
            index = lib.cosim_add_input(self._s, info.port.encode(), info.bit, level)
            if index < 0:
                raise BoardError(f"pin {pin} cannot be driven")
            self._inputs[pin] = index
        self.cycles_per_us = F_CPU_HZ // 1_000_000
        self._cyc = (ctypes.c_uint64 * 4096)()
        self._byt = (ctypes.c_uint8 * 4096)()

    def close(self) -> None:
        """Free the emulator."""
        if self._s:
            self._lib.cosim_close(self._s)
            self._s = None

    def __del__(self):
        try:
            self.close()
        except Exception:
            pass

    @property
    def cycle(self) -> int:
        """CPU cycles since reset."""
        return self._lib.cosim_cycle(self._s)

    def run_to(self, cycle: int) -> None:
        """Execute instructions until the cycle count reaches ``cycle``."""
        state = self._lib.cosim_run(self._s, cycle)
        if state:
            what = "crashed" if state == CPU_CRASHED else "stopped (sleep with interrupts off)"
            log = self._lib.cosim_last_log().decode(errors="replace").strip()
            raise BoardError(
                f"the AVR {what} at {self.cycle / (self.cycles_per_us * 1e6):.6f} s"
                + (f": {log}" if log else "")
            )

    def run_until_change(self, cycle: int) -> bool:
        """Execute until an output pin changes (True) or the count reaches ``cycle`` (False)."""
        before = self.outputs()
        if self._lib.cosim_run_until_change(self._s, cycle):
            raise BoardError(f"the AVR stopped at {self.cycle / (self.cycles_per_us * 1e6):.6f} s")
        return self.outputs() != before

    def run_to_symbol(self, address: int, max_cycle: int) -> bool:
        """Execute until the program counter reaches ``address`` (bytes); False if not by
        ``max_cycle``."""
        state = self._lib.cosim_run_to_pc(self._s, address, max_cycle)
        if state > 1:
            raise BoardError(f"the AVR stopped (state {state}) before reaching 0x{address:x}")
        return state == 0

    def outputs(self) -> int:
        """The output pins packed one byte each (first pin in the low byte): OCR or 0/255."""
        return self._lib.cosim_outputs(self._s)

    def peek(self, address: int) -> int:
        """A byte of the data space (registers, RAM)."""
        return self._lib.cosim_peek(self._s, address)

    def queue_edge(self, cycle: int, pin: int) -> None:
        """Toggle input ``pin`` at ``cycle`` (not before the cycles already queued)."""
        if self._lib.cosim_queue_edge(self._s, cycle, self._inputs[pin]) != 0:
            raise BoardError(f"cannot queue an edge on pin {pin}")

    def queue_rx(self, cycle: int, data: bytes, byte_cycles: int) -> None:
        """Bytes entering USART0's receiver, the first at ``cycle``, one each ``byte_cycles``."""
        if self._lib.cosim_queue_rx(self._s, cycle, data, len(data), byte_cycles) != 0:
            raise BoardError("cannot queue UART bytes")

    def take_tx(self) -> list[tuple[int, int]]:
        """``(cycle, byte)`` written to UDR0 since the last call."""
        out = []
        while True:
            n = self._lib.cosim_tx_take(self._s, self._cyc, self._byt, len(self._cyc))
            out.extend(zip(self._cyc[:n], self._byt[:n]))
            if n < len(self._cyc):
                return out
