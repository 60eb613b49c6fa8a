"""Real-time pacing of a running twin, and the one door through which other threads act on it.

:class:`Pacer` is a synced clock event of its own, every ``tick_us`` (20 ms, a multiple of
the record grid). At each tick, with the physics brought up to the tick's instant by the
loop as for any synced event, it

Reasons and measurements: docs/how-to/live.md#amr_twinlivepacer."""

from __future__ import annotations

import logging
import queue
import threading
import time
from concurrent.futures import Future
from typing import Any, Callable

LOG = logging.getLogger(__name__)

TICK_US = 20_000
"""Default period of the pacing event, us (50 Hz: the viewers' refresh, the commands' latency)."""
MAX_LAG_S = 1.0
"""Wall seconds behind the paced schedule after which the reference is moved up."""
PAUSED_POLL_S = 0.005
"""How often a paused twin runs the calls queued meanwhile, wall s (a service call's latency while
paused)."""


class PacerClosed(RuntimeError):
    """The twin is no longer running: a call cannot be made."""


class Pacer:
    """Pace ``twin`` to ``rate`` simulated seconds per wall second and run other threads' calls.

    Parameters
    ----------
    twin : Twin
        The twin; the pacing event is scheduled on its clock from now on.
    rate : float
        Simulated seconds per wall-clock second; 0 runs as fast as possible.
    tick_us : int
        Period of the pacing event, us; a positive multiple of the twin's record grid.
    """

    def __init__(self, twin, rate: float = 1.0, tick_us: int = TICK_US):
        if not rate >= 0 or rate == float("inf"):
            raise ValueError(f"rate: {rate} must be a finite number >= 0 (0: as fast as possible)")
        if tick_us <= 0 or tick_us % twin.grid_us:
            raise ValueError(
                f"tick_us: {tick_us} must be a positive multiple of the record grid "
                f"({twin.grid_us} us)"
            )
        self.twin, self.rate, self.tick_us = twin, float(rate), int(tick_us)
        self.sinks: list = []
        """Objects with ``flush(t_us)`` (and ``close()``), called at every tick."""
        self.lag_resets = 0
        self.ticks = 0
        self._calls: queue.SimpleQueue = queue.SimpleQueue()
        self._closed = False
        self._paused = threading.Event()
        self._lock = threading.Lock()
        self._wall0: float | None = None
        self._sim0_us = 0
        now = twin.clock.now_us
        twin.clock.schedule((now // self.tick_us + 1) * self.tick_us, self._tick)

    # -- the pacing event ------------------------------------------------------------
    def _tick(self) -> None:
        if self._closed:
            return
        clock = self.twin.clock
        now_us = clock.now_us
        self.ticks += 1
        if self.rate:
            for sink in self.sinks:
                release = getattr(sink, "release", None)
                if release is not None:
                    try:
                        release(now_us, self.wait_until)
                    except Exception:  # noqa: BLE001 - as flush: a sink's failure must not stop the twin
                        LOG.exception(
                            "live sink %s failed at t=%.3f s", type(sink).__name__, now_us * 1e-6
                        )
        self.wait_until(now_us)
        self.run_calls()
        self.flush(now_us)
        if self._paused.is_set():
            self._hold()
        clock.schedule(now_us + self.tick_us, self._tick)

    def _hold(self) -> None:
        """Paused: run the queued calls until resumed or stopped; pace afresh from then on."""
        while self._paused.is_set() and not self.twin.stopped:
            time.sleep(PAUSED_POLL_S)
            self.run_calls()
        self._paused.clear()
        self._wall0 = None

    # -- pausing (any thread) ------------------------------------------------------------
    def pause(self) -> None:
        """Hold the twin at the next tick (it keeps running the queued calls) until
        :meth:`resume`."""
        self._paused.set()

    def resume(self) -> None:
        """Let a paused twin run on."""
        self._paused.clear()

    def wait_until(self, t_us: int) -> None:
        """Sleep until the wall time of simulated ``t_us`` (paced; the first call sets the
        reference)."""
        if self.rate == 0:
            return
        wall = time.perf_counter()
        if self._wall0 is None:
            self._wall0, self._sim0_us = wall, t_us
            return
        target = self._wall0 + (t_us - self._sim0_us) * 1e-6 / self.rate
        if target > wall:
            time.sleep(target - wall)
        elif wall - target > MAX_LAG_S:
            if not self.lag_resets:
                LOG.warning(
                    "the twin runs behind --rate %g (%.1f s late at t=%.2f s); pacing from now on",
                    self.rate,
                    wall - target,
                    t_us * 1e-6,
                )
            self.lag_resets += 1
            self._wall0, self._sim0_us = wall, t_us

    def flush(self, t_us: int) -> None:
        """Hand each sink what happened up to ``t_us`` (at a tick, and once at the end of a run)."""
        for sink in self.sinks:
            try:
                sink.flush(t_us)
            except Exception:  # noqa: BLE001 - a viewer's failure must not stop the twin
                LOG.exception("live sink %s failed at t=%.3f s", type(sink).__name__, t_us * 1e-6)

    # -- calls from other threads --------------------------------------------------------
    def post(self, func: Callable[[], Any]) -> Future:
        """Queue ``func()`` to run at the next tick in the twin's thread; returns its future.

        Raises :class:`PacerClosed` once the twin has stopped.
        """
        future: Future = Future()
        with self._lock:
            if self._closed:
                raise PacerClosed("the twin is not running")
            self._calls.put((func, future))
        return future

    def call(self, func: Callable[[], Any], timeout_s: float = 10.0) -> Any:
        """Run ``func()`` at the next tick and return its result (or raise its exception)."""
        return self.post(func).result(timeout=timeout_s)

    def run_calls(self) -> int:
        """Run the queued calls now (the twin's thread); a call that raises is logged and
        skipped."""
        n = 0
        while True:
            try:
                func, future = self._calls.get_nowait()
            except queue.Empty:
                return n
            n += 1
            if not future.set_running_or_notify_cancel():
                continue
            try:
                future.set_result(func())
            except Exception as exc:  # noqa: BLE001 - nothing another thread sends may stop the twin
                LOG.error(
                    "call from another thread failed at t=%.3f s: %s",
                    self.twin.clock.now_us * 1e-6,
                    exc,
                )
                future.set_exception(exc)

    def close(self) -> None:
        """The run is over: refuse new calls, fail the queued ones, flush and close the sinks."""
        with self._lock:
            self._closed = True
        while True:
            try:
                _func, future = self._calls.get_nowait()
            except queue.Empty:
                break
            if future.set_running_or_notify_cancel():
                future.set_exception(PacerClosed("the twin stopped before the call ran"))
        self.flush(self.twin.clock.now_us)
        for sink in self.sinks:
            try:
                sink.close()
            except Exception:  # noqa: BLE001
                LOG.exception("closing live sink %s failed", type(sink).__name__)

    @property
    def closed(self) -> bool:
        return self._closed
