"""The emulated Mega's USART0 on a pseudo-terminal, as ``/dev/ttyACM0`` is on the robot.

With ``AvrParams(serial_pty=PATH)`` the board's serial port is served to a rosserial host (the
project's ``amr_twin/ros1/serial_host.py``, or upstream's ``serial_node.py``) instead of the twin's
own PC side: :class:`PtySerialPort` opens a pseudo-terminal pair in raw mode and links ``PATH``
to its host side. :class:`~amr_twin.controllers.avr.AvrFirmware` then runs paced to wall time
(:class:`WallPacer`: at every board sync, 1 ms of simulated time, it sleeps until the wall clock
has caught up), hands the host's bytes to the board's receiver at the simulated instant they are
read, at the UART's byte rate, and writes each byte the board sends once the wall clock has passed
the instant its last bit left the wire. A byte reaches the board at most one sync period (plus the
sleep's granularity) after the host wrote it.

``PATH`` must not exist (a link left dangling by a killed twin, whose pseudo-terminal is gone, is
replaced); it is removed when the port closes.
"""

from __future__ import annotations

import array
import errno
import fcntl
import os
import termios
import time
import tty
from dataclasses import dataclass

MAX_LAG_S = 1.0
"""Wall seconds behind the paced schedule after which the wall-clock reference is moved up."""


def pty_problem(path: str) -> str | None:
    """Why a pseudo-terminal cannot be linked at ``path`` now (None: it can)."""
    if os.path.exists(path):
        return f"{path} exists (a serial port or file): give a path that does not"
    folder = os.path.dirname(os.path.abspath(path))
    if not os.path.isdir(folder):
        return f"its folder {folder} does not exist"
    if not os.access(folder, os.W_OK | os.X_OK):
        return f"its folder {folder} is not writable"
    return None


@dataclass
class WallPacer:
    """Pace simulated time to the wall clock: :meth:`sleep_until` returns once the wall clock has
    reached simulated ``t_us`` (``rate`` simulated s per wall s). The first call fixes the
    reference; a lag beyond
    :data:`MAX_LAG_S` moves it up (:attr:`lag_resets` counts it).
    """

    rate: float = 1.0
    wall0: float | None = None
    sim0_us: int = 0
    lag_resets: int = 0

    def sleep_until(self, t_us: int) -> None:
        wall = time.perf_counter()
        if self.wall0 is None:
            self.wall0, self.sim0_us = wall, t_us
            return
        target = self.wall0 + (t_us - self.sim0_us) * 1e-6 / self.rate
        if target > wall:
            time.sleep(target - wall)
        elif wall - target > MAX_LAG_S:
            self.lag_resets += 1
            self.wall0, self.sim0_us = wall, t_us

    def wall_of(self, t_us: int) -> float:
        """The ``time.perf_counter()`` instant that simulated ``t_us`` is paced to."""
        return (self.wall0 or 0.0) + (t_us - self.sim0_us) * 1e-6 / self.rate


class PtySerialPort:
    """A pseudo-terminal pair in raw mode, its host side linked at ``path``; non-blocking I/O on the
    twin's side.

    Raises ValueError (one line) when ``path`` cannot be made (:func:`pty_problem`).
    """

    def __init__(self, path: str):
        self.path = str(path)
        if os.path.islink(self.path) and not os.path.exists(self.path):
            os.unlink(self.path)  # dangling: the pseudo-terminal of a twin that was killed
        problem = pty_problem(self.path)
        if problem:
            raise ValueError(f"--serial-pty {self.path}: {problem}")
        self._master, self._slave = os.openpty()
        tty.setraw(self._slave)  # bytes pass as they are: no echo, no line discipline
        tty.setraw(self._master)
        os.set_blocking(self._master, False)
        self.device = os.ttyname(self._slave)
        try:
            os.symlink(self.device, self.path)
        except OSError as exc:
            self._close_fds()
            raise ValueError(f"--serial-pty {self.path}: cannot link it ({exc.strerror})") from None
        self.bytes_in = self.bytes_out = self.bytes_dropped = 0

    def read(self) -> bytes:
        """What the host wrote since the last call (b"" if nothing)."""
        chunks = []
        while True:
            try:
                data = os.read(self._master, 4096)
            except BlockingIOError:
                break
            except OSError as exc:  # EIO: no host side open
                if exc.errno == errno.EIO:
                    break
                raise
            if not data:
                break
            chunks.append(data)
        out = b"".join(chunks)
        self.bytes_in += len(out)
        return out

    @property
    def in_waiting(self) -> int:
        """Bytes the host wrote that the twin has not read yet (pyserial's name)."""
        count = array.array("i", [0])
        fcntl.ioctl(self._master, termios.FIONREAD, count)
        return count[0]

    def write(self, data: bytes) -> None:
        """Send ``data`` to the host; what the pseudo-terminal cannot take now is dropped and
        counted."""
        try:
            n = os.write(self._master, data)
        except (BlockingIOError, OSError):
            n = 0
        self.bytes_out += n
        self.bytes_dropped += len(data) - n

    def _close_fds(self) -> None:
        for fd in (self._master, self._slave):
            try:
                os.close(fd)
            except OSError:
                pass

    def close(self) -> None:
        """Remove the link and close the pseudo-terminal."""
        if os.path.islink(self.path) and os.readlink(self.path) == self.device:
            os.unlink(self.path)
        self._close_fds()
