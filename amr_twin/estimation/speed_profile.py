"""One wheel's estimated signed speed: knots ``(t_us, rpm)``, linear between knots and held after
the last, and the revolutions it covers up to an instant (pure, no bus or clock)."""

from __future__ import annotations

from bisect import bisect_right

PAST_KNOTS = 256
"""Trimmed knots a :class:`SpeedProfile` keeps to count revolutions back in time (a window of the
thesis firmware reaches one revolution back: some 10 knots at most)."""


class SpeedProfile:
    """Estimated signed speed of one wheel: knots (t_us, rpm), linear between, held after."""

    def __init__(self, t_us: int, rpm: float = 0.0):
        self.t_us: list[int] = [int(t_us)]
        self.rpm: list[float] = [float(rpm)]
        self._past: list[
            tuple[int, float, float]
        ] = []  # trimmed knots: (t_us, rpm, revolutions up to t_us)
        self._revs0 = 0.0  # revolutions from the start up to t_us[0]
        self.assumed_us: int | None = None  # knots after this instant are a stand-in, not knowledge

    @property
    def last_us(self) -> int:
        return self.t_us[-1]

    @property
    def last_rpm(self) -> float:
        return self.rpm[-1]

    def known_us(self, t_us: int) -> int:
        """Time of the last knot at or before ``t_us`` (at most :attr:`assumed_us`)."""
        known = self.t_us[max(bisect_right(self.t_us, t_us) - 1, 0)]
        return known if self.assumed_us is None else min(known, self.assumed_us)

    def step(self, t_us: int, rpm: float) -> None:
        """The speed becomes ``rpm`` at ``t_us`` (held value until then)."""
        t_us = max(int(t_us), self.last_us)
        self.t_us += [t_us, t_us]
        self.rpm += [self.last_rpm, float(rpm)]

    def point(self, t_us: int, rpm: float) -> None:
        """The speed is ``rpm`` at ``t_us`` (linear from the last knot; not before it)."""
        self.t_us.append(max(int(t_us), self.last_us))
        self.rpm.append(float(rpm))

    def window(self, t0_us: int, t1_us: int, rpm: float) -> None:
        """Mean speed ``rpm`` over ``[t0_us, t1_us]`` (t0 clipped at the last knot)."""
        t1_us = max(int(t1_us), self.last_us)
        t0_us = min(max(int(t0_us), self.last_us), t1_us)
        self.t_us += [t0_us, t1_us]
        self.rpm += [float(rpm), float(rpm)]

    def segment(self, t_us: int) -> tuple[int, float, int, float]:
        """The linear piece (t0, r0, t1, r1) in force just after ``t_us``."""
        i = max(bisect_right(self.t_us, t_us) - 1, 0)
        if i + 1 >= len(self.t_us):
            return self.t_us[i], self.rpm[i], self.t_us[i], self.rpm[i]
        return self.t_us[i], self.rpm[i], self.t_us[i + 1], self.rpm[i + 1]

    def at(self, t_us: float, seg: tuple[int, float, int, float]) -> float:
        """Speed at ``t_us`` on the piece ``seg``, RPM."""
        t0, r0, t1, r1 = seg
        if t1 <= t0:
            return r0
        return r0 + (r1 - r0) * (t_us - t0) / (t1 - t0)

    def cut(self, t_us: int) -> None:
        """Forget the knots after ``t_us`` (assumptions about the future)."""
        if self.last_us <= t_us:
            return
        i = bisect_right(self.t_us, t_us)
        value = self.at(t_us, self.segment(t_us))
        self.t_us = self.t_us[:i] + [int(t_us)]
        self.rpm = self.rpm[:i] + [value]

    def trim(self, t_us: int) -> None:
        """Forget the knots before ``t_us``, keeping the speed in force from it (and their
        revolutions)."""
        i = max(bisect_right(self.t_us, t_us) - 1, 0)
        value = self.at(t_us, self.segment(t_us))
        if t_us > self.t_us[0]:
            revs = self._revs0
            for k in range(i + 1):
                self._past.append((self.t_us[k], self.rpm[k], revs))
                t_next, r_next = (
                    (self.t_us[k + 1], self.rpm[k + 1]) if k < i else (int(t_us), value)
                )
                revs += (t_next - self.t_us[k]) * (self.rpm[k] + r_next) / 120e6
            self._revs0 = revs
            del self._past[:-PAST_KNOTS]
        self.t_us = [int(t_us)] + self.t_us[i + 1 :]
        self.rpm = [value] + self.rpm[i + 1 :]

    def revolutions(self, t0_us: float, t1_us: float) -> float:
        """Signed revolutions the profile implies over ``[t0_us, t1_us]`` (trimmed knots included,
        as far back as :data:`PAST_KNOTS` of them reach; at rest before)."""
        return self._revolutions_at(t1_us) - self._revolutions_at(t0_us)

    def _revolutions_at(self, t_us: float) -> float:
        knots = self._past + [(self.t_us[0], self.rpm[0], self._revs0)]
        if t_us <= knots[0][0]:
            return knots[0][2]
        k = max(bisect_right([kn[0] for kn in knots], t_us) - 1, 0)
        if k < len(knots) - 1:
            (ta, ra, revs), (tb, rb, _) = knots[k], knots[k + 1]
        else:  # on the live knots
            k = max(bisect_right(self.t_us, t_us) - 1, 0)
            revs = self._revs0
            for j in range(k):
                revs += (self.t_us[j + 1] - self.t_us[j]) * (self.rpm[j] + self.rpm[j + 1]) / 120e6
            ta, ra = self.t_us[k], self.rpm[k]
            tb, rb = (self.t_us[k + 1], self.rpm[k + 1]) if k + 1 < len(self.t_us) else (ta, ra)
        r = ra if tb <= ta else ra + (rb - ra) * (t_us - ta) / (tb - ta)
        return revs + (t_us - ta) * (ra + r) / 120e6
