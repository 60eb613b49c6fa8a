"""The twin of ``amr-twin client`` advanced in a background thread, paced to real time (and served
live or on a ROS 1 graph), while the menu reads the terminal.
"""

from __future__ import annotations

import threading
from typing import Callable, Optional


class RealTimeTwin:
    """A :class:`~amr_twin.assembly.twin.Twin` advanced in a thread at ``rate`` x real time.

    The pacing is :mod:`amr_twin.live.pacer`'s (a clock event every 20 ms that sleeps to the
    wall clock), so the run is the one an unpaced twin computes; a menu choice runs in the
    twin's thread at the next pacing event (:meth:`call`). With ``live`` the twin is also
    served live (:class:`~amr_twin.live.session.LiveSession`: Foxglove or Rerun).

    Parameters
    ----------
    twin : Twin
        The twin to run.
    rate : float
        Simulated seconds per wall-clock second (> 0).
    live : LiveOptions, optional
        Serve the twin live as well (its ``rate`` is this one).
    say : callable
        Where the live session prints its addresses.
    ros1 : Ros1Options, optional
        Put the twin on a ROS 1 graph as well (:mod:`amr_twin.ros1.session`).
    """

    PIECE_S = 0.1
    """Simulated seconds per ``advance`` call: a stop request waits at most this long (on the record
    grid)."""

    def __init__(self, twin, rate: float = 1.0, live=None, say=print, ros1=None):
        from dataclasses import replace

        from amr_twin.live.pacer import Pacer

        self.twin, self.rate = twin, float(rate)
        self.session = None
        if live is not None:
            from amr_twin.live.session import LiveSession

            self.session = LiveSession(twin, replace(live, rate=self.rate), say=say)
            self.pacer = self.session.pacer
        else:
            self.pacer = Pacer(twin, self.rate)
        self.ros1 = None
        if ros1 is not None:
            from amr_twin.ros1.session import Ros1Session

            if live is None:
                from amr_twin.controllers.diff_drive import DiffDriveNode
                from amr_twin.live.session import CMD_TIMEOUT_S

                DiffDriveNode(twin.bus, twin.clock, twin.client, cmd_timeout_s=CMD_TIMEOUT_S)
            self.ros1 = Ros1Session(twin, self.pacer, ros1, say=say)
        self.error: Optional[BaseException] = None
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, name="twin", daemon=True)

    def start(self) -> "RealTimeTwin":
        self._thread.start()
        return self

    def _run(self) -> None:
        from amr_twin.sim.bounds import MAX_RUN_S

        try:
            while not self._stop.is_set():
                if (
                    self.twin.t_s + self.PIECE_S > MAX_RUN_S + 1e-9
                ):  # a run keeps its series in memory
                    raise RuntimeError(
                        f"it reached the bound of a run, {MAX_RUN_S:g} simulated s (its 100 Hz "
                        "series are kept in memory): start the client again"
                    )
                self.twin.advance(self.PIECE_S)
        except Exception as exc:  # noqa: BLE001 - reported to the user by the menu
            self.error = exc
        finally:
            (self.session or self.pacer).close()
            if self.ros1 is not None:
                self.ros1.close()

    def call(self, func: Callable[[], int]) -> int:
        """Run ``func`` (a client call) in the twin's thread at the next pacing event."""
        return self.pacer.call(func)

    def close(self) -> None:
        self._stop.set()
        self._thread.join(timeout=5.0)
