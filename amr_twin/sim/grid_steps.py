"""A chunk of the loop's physics in one C call: the grid loop of
:meth:`amr_twin.assembly.twin.Twin._step_physics`.

Between two events the loop steps the physics to each record-grid instant (every 10 ms),
keeps the loop sensors' row there and runs the grid samplers. When every sampler of the
twin has a C form (its ``grid_native``: a :class:`Sampler`; the rolling resistance, the
battery, the actors' motion, the collision monitor while no collision is open, and
:class:`~amr_twin.sim.grid_rows.GridRows` keepers: a sweep point's support loads, the IMU's true
values, the LiDAR's laser poses),
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
