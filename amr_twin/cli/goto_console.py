"""The console of a running ``run goto``: a progress line on stderr, and a Ctrl-C that stops the
robot first.

- The progress line: at most one every ``PERIOD_S`` wall seconds, the first after as long (a short
run
  prints none), on stderr (never in ``--json``'s stdout): simulated time, the active goal, the
  distance left on its plan, the robot's speed (the localisation's), the recoveries so far and the
  time left at the rate the distance left fell over the last ``RATE_WINDOW_S`` simulated seconds.
- Ctrl-C: the first SIGINT cancels the goals (the navigator ramps the robot to a stop; the run's
outputs
  are written and the command exits :data:`EXIT_CANCELED`); a second one stops at once
  (KeyboardInterrupt: exit 130, nothing written).
"""

from __future__ import annotations

import math
import signal
import threading
import time
from collections import deque

EXIT_CANCELED = 6
PERIOD_S = 2.0
"""Wall seconds between two progress lines (and before the first)."""
RATE_WINDOW_S = 10.0
"""Simulated seconds over which the rate of progress (for the time left) is taken."""


class GotoConsole:
    """Progress lines to ``say`` and the Ctrl-C handling of one goto run (a context manager: it
    holds SIGINT).

    Called as ``console(navigator, t_s)`` every simulated half second (``navigate``'s ``progress``).
    ``wall``: the wall clock, s (a test's own)."""

    def __init__(self, say, wall=time.monotonic, period_s: float | None = None):
        self.say, self.wall = say, wall
        self.period_s = PERIOD_S if period_s is None else period_s
        self.interrupts = 0
        self.canceled_at_s: float | None = None
        """Simulated time the goals were cancelled at (None: they were not)."""
        self._next_line = wall() + self.period_s
        self._left: deque = deque()  # (t_s, goal index, distance left m)
        self._previous = None

    # -- SIGINT ------------------------------------------------------------------------------
    def __enter__(self):
        if threading.current_thread() is threading.main_thread():
            self._previous = signal.signal(signal.SIGINT, self._on_sigint)
        return self

    def __exit__(self, *exc) -> None:
        if self._previous is not None:
            signal.signal(signal.SIGINT, self._previous)
            self._previous = None

    def _on_sigint(self, _signum, _frame) -> None:
        self.interrupts += 1
        if self.interrupts > 1:
            raise KeyboardInterrupt
        self.say(
            "goto: Ctrl-C: stopping the robot and writing the outputs (Ctrl-C again to quit at "
            "once, "
            "writing nothing)"
        )

    # -- each simulated half second ----------------------------------------------------------------
    def __call__(self, nav, t_s: float) -> None:
        if self.interrupts and self.canceled_at_s is None:
            self.canceled_at_s = t_s
            nav.cancel(f"canceled by the user (Ctrl-C) at t = {t_s:.1f} s")
            return
        goal = nav.active
        if goal is None:
            return
        index = next(i for i, o in enumerate(nav.outcomes) if o is goal)
        left = nav.distance_left_m
        if math.isfinite(left):
            self._left.append((t_s, index, left))
        while self._left and (self._left[0][0] < t_s - RATE_WINDOW_S or self._left[0][1] != index):
            self._left.popleft()
        now = self.wall()
        if now < self._next_line:
            return
        self._next_line = now + self.period_s
        self.say(self.line(nav, t_s, index, left))

    def line(self, nav, t_s: float, index: int, left: float) -> str:
        """The progress line (module docstring)."""
        x, y = nav.outcomes[index].goal[:2]
        recoveries = sum(len(o.recoveries) for o in nav.outcomes)
        speed = nav.pose_source.velocity[0] if nav.pose_source.ready else 0.0
        where = "planning" if not math.isfinite(left) else f"{left:.1f} m left"
        eta = "time left unknown"
        if len(self._left) > 1 and math.isfinite(left):
            (t0, _, left0), (t1, _, left1) = self._left[0], self._left[-1]
            rate = (left0 - left1) / (t1 - t0)
            if rate > 0.05:
                eta = f"about {left / rate:.0f} s left"
        return (
            f"goto: t {t_s:.1f} s, goal {index + 1} of {len(nav.outcomes)} ({x:g}, {y:g}): "
            f"{where}, "
            f"{speed:.2f} m/s, {recoveries} recover{'y' if recoveries == 1 else 'ies'}, {eta}"
        )
