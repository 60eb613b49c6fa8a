"""A chunk of the loop's physics in one C call: the grid loop of
:meth:`amr_twin.assembly.twin.Twin._step_physics`.

Between two events the loop steps the physics to each record-grid instant (every 10 ms),
keeps the loop sensors' row there and runs the grid samplers. When every sampler of the
twin has a C form (its ``grid_native``: a :class:`Sampler`; the rolling resistance, the
battery, the actors' motion, the collision monitor while no collision is open, and :class:`GridRows`
keepers: a sweep point's support loads, the IMU's true values, the LiDAR's laser poses),
:class:`GridStepper` runs that loop in ``grid_steps.c``: mj_step through a pointer into
libmujoco, the row copied, the samplers' helpers called in order; one call a chunk against
one Python round trip and three to five helper calls an instant (a sweep point's 800 instants
cost ~12 ms of Python). A sampler may hand an instant back (:data:`CHANGED`: the contacts
changed; :data:`ROW`: its room is full, or its owner has work due, as a LiDAR cast): its
``grid_resume`` (or itself) and the samplers after it then run in Python there. Any other
sampler (a recording's body poses, a live view's rows) keeps the Python loop, which is this
module's Python twin: the same bits (tests/sim/test_grid_steps.py).

Part of the physics layer (``PHYSICS_LAYER``): the grid loop in C: ``mj_step`` to each grid instant
and the rows read where they lie in MjData.
"""

from __future__ import annotations

import ctypes
from pathlib import Path

import numpy as np

from amr_twin.base.c_layout import register
from amr_twin.base.native_build import address, mujoco_address, open_helper

PHYSICS_LAYER = True

C_SOURCE = Path(__file__).with_name("grid_steps.c")
CALL2, CALL3, CALL4, CHANGED, ROW, TIMED = range(6)
"""How a :class:`Sampler`'s function is called: with 2, 3 or 4 of its arguments; as a test whose
non-zero result hands the instant to Python; as a row keeper ``f(a0, a1, a2, row)``; with 2 of its
arguments and the instant, us (int64: ``f(a0, a1, t_us)``)."""
_P = ctypes.c_void_p
NEVER_BEFORE, NEVER_DUE = -(1 << 62), 1 << 62


class Sampler(ctypes.Structure):
    """``gs_sampler`` of grid_steps.c: a grid sampler's C form."""

    _fields_ = [
        ("kind", ctypes.c_int),
        ("width", ctypes.c_int),
        ("cap", ctypes.c_int),
        ("n", ctypes.c_int),
        ("period_us", ctypes.c_int64),
        ("start_us", ctypes.c_int64),
        ("due_us", ctypes.c_int64),
        ("fn", _P),
        ("a", _P * 4),
        ("out", _P),
    ]


def sampler(kind: int, function, *args, period_us: int = 1) -> Sampler:
    """A :class:`Sampler` calling the helper ``function`` (a ctypes function of a loaded helper)
    with ``args`` (addresses, or ctypes structures and arrays: their addresses), at the grid
    instants that are multiples of ``period_us``."""
    if int(period_us) < 1:
        raise ValueError(f"grid sampler: period_us {period_us} must be >= 1")
    s = Sampler(
        kind=kind,
        period_us=int(period_us),
        start_us=NEVER_BEFORE,
        due_us=NEVER_DUE,
        fn=ctypes.cast(function, _P).value,
    )
    for i, arg in enumerate(args):
        s.a[i] = arg if isinstance(arg, int) else ctypes.addressof(arg)
    s._keep = args  # the arguments outlive the sampler
    return s


class _Context(ctypes.Structure):
    _fields_ = [
        ("step", _P),
        ("user_error", _P),
        ("m", _P),
        ("d", _P),
        ("sensors", _P),
        ("ncol", ctypes.c_int),
        ("rows_cap", ctypes.c_int),
        ("rows", _P),
        ("every", ctypes.c_int),
        ("grid_us", ctypes.c_int64),
        ("s", ctypes.POINTER(ctypes.POINTER(Sampler))),
        ("ns", ctypes.c_int),
        ("handoff", ctypes.c_int),
        ("message", ctypes.c_char * 256),
    ]


register(C_SOURCE, gs_sampler=Sampler, gs_ctx=_Context)


class GridStepper:
    """Runs the grid loop of a twin's physics in C (module notes).

    ``physics``: :class:`amr_twin.sim.physics.Physics`; ``ncol``: the loop sensors' values a row
    (the first ``ncol`` of ``sensordata``); ``every``: steps between grid instants; ``dt_us``:
    the timestep, us.
    """

    def __init__(self, lib: ctypes.PyDLL, physics, ncol: int, every: int, dt_us: int):
        m, d = physics.model, physics.data
        self._run = lib.gs_run
        self._run.restype, self._run.argtypes = (
            ctypes.c_int,
            [_P, ctypes.c_int, ctypes.c_int, ctypes.c_int64],
        )
        c = self._ctx = _Context(
            step=mujoco_address("mj_step"),
            user_error=mujoco_address("mju_user_error"),
            m=m._address,
            d=d._address,
            sensors=address(d.sensordata),
            ncol=ncol,
            every=every,
            grid_us=every * dt_us,
            handoff=-1,
        )
        self._ctx_at = ctypes.addressof(c)
        self._keep = (m, d)  # the model and data outlive every call
        self.rows = np.zeros((0, ncol))
        """(n, ncol) the rows of the last :meth:`run`, at the instants it reached (the first ``n``
        valid)."""
        self._sets: dict[tuple, tuple] = {}
        self.resume: list = []
        """Per sampler of the set in use, what runs in Python for an instant handed back."""

    def use(self, samplers: list) -> bool:
        """Take ``samplers`` (the twin's grid samplers, in order) for the next runs; False when one
        has no C form now (the Python loop runs)."""
        natives = [getattr(s, "grid_native", None) for s in samplers]
        if None in natives:
            return False
        key = tuple(map(id, natives))
        kept = self._sets.get(key)
        if kept is None:
            if len(self._sets) > 16:
                self._sets.clear()
            pointers = (ctypes.POINTER(Sampler) * len(natives))(
                *(ctypes.pointer(s) for s in natives)
            )
            resume = [getattr(s, "grid_resume", s) for s in samplers]
            kept = self._sets[key] = (pointers, resume, natives)  # natives: their ids stay theirs
        pointers, self.resume, _ = kept
        self._ctx.s, self._ctx.ns = pointers, len(pointers)
        return True

    def run(self, nfirst: int, nmarks: int, t_first_us: int) -> tuple[int, int]:
        """Step ``nfirst`` steps to the first of ``nmarks`` grid instants (at ``t_first_us``), then
        ``every`` to each next; ``(reached, handoff)``: the instants reached (their rows in
        :attr:`rows`) and -1, or the index of the sampler that hands the last one to Python (the
        samplers before it ran). Raises ``mujoco.FatalError`` on a MuJoCo error, as mj_step does."""
        c = self._ctx
        if len(self.rows) < nmarks:
            self.rows = np.zeros((max(nmarks, 2 * len(self.rows), 64), c.ncol))
            c.rows, c.rows_cap = address(self.rows), len(self.rows)
        reached = self._run(self._ctx_at, nfirst, nmarks, t_first_us)
        if reached == -2:
            raise ValueError(f"grid steps: nfirst {nfirst} and every {c.every} must be >= 1")
        if reached < 0:
            import mujoco

            raise mujoco.FatalError(c.message.decode(errors="replace"))
        return reached, c.handoff


def grid_stepper(
    physics, ncol: int, every: int, dt_us: int, native: bool = True
) -> GridStepper | None:
    """The C grid loop for ``physics`` when its helper builds and loads (and ``native``), else
    None."""
    lib, _engine = open_helper(C_SOURCE, native)
    return GridStepper(lib, physics, ncol, every, dt_us) if lib is not None else None


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
