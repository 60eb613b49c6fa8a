"""A grid sampler keeping rows of values at each grid instant (:class:`GridRows`), in Python or, in
the grid loop in C (:mod:`amr_twin.sim.grid_steps`), by a C helper such as :func:`gather`'s.

Part of the physics layer (``PHYSICS_LAYER``): :func:`gather` reads doubles where they lie in
MjData."""

from __future__ import annotations

import ctypes

import numpy as np

from amr_twin.base.native_build import address, open_helper
from amr_twin.sim.grid_steps import C_SOURCE, NEVER_BEFORE, NEVER_DUE, ROW, sampler

PHYSICS_LAYER = True


def gather(pointers: list[int]) -> tuple | None:
    """``c_row`` of a :class:`GridRows` whose values are the doubles at ``pointers`` (addresses
    in MjData; ``gs_gather``), or None without the helper."""
    lib, _engine = open_helper(C_SOURCE)
    if lib is None:
        return None
    at = (ctypes.c_void_p * len(pointers))(*pointers)
    return (lib.gs_gather, at, ctypes.c_int(len(pointers)), 0)


class GridRows:
    """A grid sampler keeping, every ``period_us`` from ``start_us`` on, a row: the instant (us, as
    a float) and ``width`` values, from ``row()`` (a list) in Python or, when the loop runs its
    grid in C, from ``c_row`` (a helper ``f(a0, a1, a2, double* values)`` and its three arguments);
    both must give the same values. After a row at or after :attr:`due_us`, ``after(t_us)`` runs
    (in Python: the LiDAR casts there). :attr:`rows` are the rows kept."""

    def __init__(
        self,
        width: int,
        period_us: int,
        row,
        c_row: tuple | None = None,
        after=None,
        start_us: int = NEVER_BEFORE,
    ):
        self.width, self._row, self._after = int(width), row, after
        self._buf = np.zeros((64, self.width + 1))
        self._n = 0
        self.grid_native = None
        """The :class:`Sampler` of the C form (None without one)."""
        if c_row is not None:
            fn, *args = c_row
            self.grid_native = sampler(ROW, fn, *args)
            self.grid_native.width, self.grid_native.cap = self.width + 1, len(self._buf)
            self.grid_native.out = address(self._buf)
        self._period_us, self._start_us, self._due_us = 1, int(start_us), NEVER_DUE
        self.period_us = period_us  # checked

    def _sync(self) -> None:
        if self.grid_native is not None:  # the C form's copies
            g = self.grid_native
            g.period_us, g.start_us, g.due_us = self._period_us, self._start_us, self._due_us

    @property
    def period_us(self) -> int:
        """Rows are kept at the grid instants that are multiples of this, us."""
        return self._period_us

    @period_us.setter
    def period_us(self, value: int) -> None:
        if int(value) < 1:
            raise ValueError(f"GridRows: period_us {value} must be >= 1")
        self._period_us = int(value)
        self._sync()

    @property
    def start_us(self) -> int:
        """Rows are kept from this instant on, us."""
        return self._start_us

    @property
    def due_us(self) -> int:
        """``after`` runs after a row kept at or after this instant, us."""
        return self._due_us

    @due_us.setter
    def due_us(self, value: int) -> None:
        self._due_us = int(value)
        if self.grid_native is not None:
            self.grid_native.due_us = self._due_us

    @property
    def n(self) -> int:
        """Rows kept."""
        return self.grid_native.n if self.grid_native is not None else self._n

    def _set_n(self, n: int) -> None:
        if self.grid_native is not None:
            self.grid_native.n = n
        else:
            self._n = n

    def __call__(self, t_us: int) -> bool:
        if t_us % self._period_us or t_us < self._start_us:
            return False
        self._keep(t_us)
        if t_us >= self._due_us:
            self._after(t_us)
        return False

    def grid_resume(self, t_us: int) -> bool:
        """The instant ``t_us`` handed back by the C form: its row kept (unless the room was
        full), then ``after`` if due."""
        n = self.n
        if not (n and self._buf[n - 1, 0] == t_us):
            self._keep(t_us)
        if t_us >= self._due_us:
            self._after(t_us)
        return False

    def _keep(self, t_us: int) -> None:
        g = self.grid_native
        n = g.n if g is not None else self._n
        buf = self._buf
        if n >= len(buf):  # full: twice the room (the C form keeps to the new buffer)
            buf = np.zeros((2 * len(buf), self.width + 1))
            buf[:n] = self._buf[:n]
            self._buf = buf
            if g is not None:
                g.out, g.cap = address(buf), len(buf)
        buf[n] = [t_us, *self._row()]  # one conversion of a plain list
        if g is not None:
            g.n = n + 1
        else:
            self._n = n + 1

    @property
    def rows(self) -> np.ndarray:
        """(n, 1 + width) the rows kept, in time order: a view, valid until the next row."""
        return self._buf[: self.n]

    def take(self) -> np.ndarray:
        """The rows kept (a copy), forgetting them."""
        out = self._buf[: self.n].copy()
        self._set_n(0)
        return out

    def keep_last(self) -> None:
        """Forget all rows but the newest."""
        n = self.n
        if n > 1:
            self._buf[0] = self._buf[n - 1]
            self._set_n(1)

    def clear(self) -> None:
        """Forget all rows."""
        self._set_n(0)

    def take_until(self, t_us: int) -> np.ndarray:
        """The rows kept at or before ``t_us`` (a copy), forgetting them; later rows stay."""
        n = self.n
        k = int(np.searchsorted(self._buf[:n, 0], t_us, side="right"))
        out = self._buf[:k].copy()
        self._buf[: n - k] = self._buf[k:n]
        self._set_n(n - k)
        return out
