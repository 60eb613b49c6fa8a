"""The progress checker (nav2's SimpleProgressChecker): the robot must move ``radius_m`` from where
it last did within ``time_allowance_s``, or the controller has failed to make progress. (The goal
checker is the navigator's ``_arrived``.)"""

from __future__ import annotations

import math


class ProgressChecker:
    """Fails when the robot stays within ``radius_m`` of a reference pose for
    ``time_allowance_s``."""

    def __init__(self, radius_m: float = 0.5, time_allowance_s: float = 10.0):
        self.radius_m, self.time_allowance_s = radius_m, time_allowance_s
        self._ref: tuple[float, float, float] | None = None

    def reset(self) -> None:
        self._ref = None

    def check(self, t_s: float, x_m: float, y_m: float) -> bool:
        """True while progress is made (a new reference when the robot has moved far enough)."""
        if self._ref is None or math.hypot(x_m - self._ref[1], y_m - self._ref[2]) >= self.radius_m:
            self._ref = (t_s, x_m, y_m)
            return True
        return t_s - self._ref[0] <= self.time_allowance_s
