"""Load-dependent rolling resistance of the tyres and the ball casters.

Reasons and measurements: docs/explanation/tyres.md#amr_twinsimrolling_resistance.

Part of the physics layer (``PHYSICS_LAYER``): a grid sampler in C: reads the contact loads and
wheel speeds from MjData and writes ``qfrc_applied``."""

from __future__ import annotations

import ctypes
import math
from pathlib import Path

import numpy as np

from amr_twin.model.config import TwinConfig
from amr_twin.sim.grid_rows import GridRows
from amr_twin.sim.grid_steps import CALL4, sampler
from amr_twin.base.c_layout import register
from amr_twin.base.native_build import open_helper

PHYSICS_LAYER = True

C_SOURCE = Path(__file__).with_name("rolling_resistance.c")

SUPPORT_ROW = 19
"""Values in a row of :meth:`RollingResistance.support_rows`."""
BALL_SPEED_EPS_M_S = 0.005
"""Ball speed below which the caster resistance fades linearly to zero, m/s."""


class _Params(ctypes.Structure):
    """``rr_params`` of rolling_resistance.c."""

    _fields_ = [
        ("tyre_qpos", ctypes.c_int * 2),
        ("tyre_dof", ctypes.c_int * 2),
        ("caster_qpos", ctypes.c_int * 4),
        ("caster_dof", ctypes.c_int * 4),
        ("ball_body", ctypes.c_int * 4),
        ("base", ctypes.c_int),
        ("root_dof", ctypes.c_int),
        ("wheel_dof", ctypes.c_int * 2),
        ("ngeom", ctypes.c_int),
        ("support_of_geom", ctypes.POINTER(ctypes.c_int)),
        ("k_t", ctypes.c_double),
        ("c_t", ctypes.c_double),
        ("f0_c", ctypes.c_double),
        ("k_c", ctypes.c_double),
        ("c_c", ctypes.c_double),
        ("tyre_arm_m", ctypes.c_double),
        ("motor_friction", ctypes.c_double * 2),
        ("ball_crr", ctypes.c_double),
        ("ball_speed_eps", ctypes.c_double),
    ]


register(C_SOURCE, rr_params=_Params)


class RollingResistance:
    """Updates the tyres' and casters' rolling resistance from the present loads.

    Call :attr:`update` (``update(t_us)``) on the record grid: the C helper, or
    :meth:`__call__` (its Python twin) without one; :attr:`loads` holds the normal loads
    it used, N: wheel left, right, casters fl, fr, rl, rr. ``native=False`` forces the
    Python twin.
    """

    def __init__(self, physics, cfg: TwinConfig, native: bool = True):
        import mujoco

        self.physics = physics
        m, d = physics.model, physics.data
        self._qpos, self._qvel, self._xmat, self._xpos = d.qpos, d.qvel, d.xmat, d.xpos
        self._friction, self._qfrc = m.dof_frictionloss, d.qfrc_applied
        w, k, g = cfg.wheel, cfg.caster, cfg.sim.gravity_m_s2

        def joint(name):
            j = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, physics.prefix + name)
            return int(m.jnt_qposadr[j]), int(m.jnt_dofadr[j])

        self._tyres = [joint(f"wheel_{s}_tyre") for s in ("left", "right")]
        self._k_t, self._c_t = w.tyre_stiffness_n_m, w.tyre_damping_n_s_m
        self._wheel_dof = [int(v) for v in physics.wheel_dof]
        self._motor_friction = [float(m.dof_frictionloss[v]) for v in self._wheel_dof]
        self._tyre_arm_m = w.rolling_resistance * w.radius_m
        casters = [name for name in physics.support.geoms if name.startswith("caster_")]
        self._casters = [joint(f"{name}_joint") for name in casters]
        self._ball_body = [int(m.geom_bodyid[physics.support.geoms[name]]) for name in casters]
        ball_kg = float(m.body_mass[self._ball_body[0]])
        self._k_c, self._c_c = k.stiffness_n_m, k.damping_n_s_m
        self._f0_c = k.preload_n + ball_kg * g
        self._ball_crr = k.rolling_resistance
        self._base = physics.base_body
        self._root_dof = int(physics.root_dof)
        # support index (0-5) of every geom, -1 for the others
        self._support_of_geom = physics.support.of_geom
        self._loads = [0.0] * 6
        self._fast = (
            d.qpos,
            d.qvel,
            d.xmat[self._base],
            d.xpos,
            m.dof_frictionloss,
            d.qfrc_applied,
            *self._tyres,
            tuple(self._casters),
            tuple(self._ball_body),
            self._base,
            self._k_t,
            self._c_t,
            self._f0_c,
            self._k_c,
            self._c_c,
            self._tyre_arm_m,
            tuple(self._motor_friction),
            tuple(self._wheel_dof),
            self._ball_crr,
            self._root_dof,
        )
        """Everything :meth:`__call__` reads, in one tuple (MjData's arrays are views: they stay
        put)."""
        self.update = self.__call__
        """The grid sampler: the C helper when built, else :meth:`__call__`."""
        self.contact_loads = lambda: physics.support.normal_forces_n().tolist()
        """``contact_loads()``: (6,) list,
        :meth:`amr_twin.sim.support.Support.normal_forces_n` (the C helper's
        ``rr_contact_loads`` when built: the same bits, ~0.5 against ~10 us)."""
        self._loads_c = None
        lib, self.engine = open_helper(C_SOURCE, native)
        """Which runs: ``"C"`` or ``"Python (<why>)"``."""
        if lib is not None:
            self._use_native(lib, m, d)

    def _use_native(self, lib, m, d) -> None:
        p = _Params()
        (p.tyre_qpos[0], p.tyre_dof[0]), (p.tyre_qpos[1], p.tyre_dof[1]) = self._tyres
        for i, (qa, va) in enumerate(self._casters):
            p.caster_qpos[i], p.caster_dof[i] = qa, va
        for i, body in enumerate(self._ball_body):
            p.ball_body[i] = body
        p.base, p.root_dof = self._base, self._root_dof
        p.wheel_dof[0], p.wheel_dof[1] = self._wheel_dof
        self._lut = np.ascontiguousarray(self._support_of_geom, dtype=np.intc)
        p.ngeom = len(self._lut)
        p.support_of_geom = self._lut.ctypes.data_as(ctypes.POINTER(ctypes.c_int))
        p.k_t, p.c_t, p.f0_c, p.k_c, p.c_c = self._k_t, self._c_t, self._f0_c, self._k_c, self._c_c
        p.tyre_arm_m = self._tyre_arm_m
        p.motor_friction[0], p.motor_friction[1] = self._motor_friction
        p.ball_crr, p.ball_speed_eps = self._ball_crr, BALL_SPEED_EPS_M_S
        self._params = p
        self._loads_c = (ctypes.c_double * 6)()
        fn = lib.rr_update
        fn.restype = None
        fn.argtypes = [ctypes.c_void_p] * 4
        args = (
            ctypes.c_void_p(m._address),
            ctypes.c_void_p(d._address),
            ctypes.byref(p),
            ctypes.cast(self._loads_c, ctypes.c_void_p),
        )
        self._keep = (m, d, args)  # the model and data outlive every call

        def update(t_us: int = 0, _fn=fn, _args=args) -> None:
            _fn(*_args)

        update.grid_native = sampler(
            CALL4, fn, m._address, d._address, p, self._loads_c
        )  # the loop's grid in C
        self.update = update
        self._row_fn = lib.rr_support_row
        contact = lib.rr_contact_loads
        contact.restype = None
        contact.argtypes = [ctypes.c_void_p] * 3
        out = (ctypes.c_double * 6)()
        contact_args = (args[1], args[2], ctypes.cast(out, ctypes.c_void_p))

        def contact_loads(_fn=contact, _args=contact_args, _out=out) -> list[float]:
            _fn(*_args)
            return _out[:]

        self.contact_loads = contact_loads

    def support_rows(self, period_us: int) -> GridRows:
        """A grid sampler keeping, every ``period_us`` (after this one's update at the same
        instant): the loads used (6), the supports' contact loads (6, :attr:`contact_loads`),
        the world z of the base's z axis (:meth:`~amr_twin.sim.physics.Physics.base_up_z`) and
        the base velocity (6, :meth:`~amr_twin.sim.physics.Physics.base_velocity`): 19 values
        a row, after its instant (``rr_support_row`` in C, the same values)."""
        physics = self.physics

        def row() -> list[float]:
            return [
                *self.loads,
                *self.contact_loads(),
                physics.base_up_z(),
                *physics.base_velocity_list(),
            ]

        c_row = None
        if self._loads_c is not None:
            c_row = (self._row_fn, self.physics.data._address, self._params, self._loads_c)
        return GridRows(SUPPORT_ROW, period_us, row, c_row)

    @property
    def loads(self) -> list[float]:
        """(6,) normal loads at the last update, N: wheel left, right, casters fl, fr, rl, rr."""
        return (
            self._loads_c[:] if self._loads_c is not None else list(self._loads)
        )  # a slice: a sixth of list()'s cost

    def __call__(self, t_us: int = 0) -> None:
        # Plain floats and locals (one attribute read of a tuple of constants): this runs on
        # cold caches every 10 ms, where each attribute lookup and MjData access counts.
        (
            qpos_v,
            qvel_v,
            xmat_base,
            xpos_v,
            fl,
            qfrc,
            (qa, va),
            (qb, vb),
            casters,
            balls,
            base,
            k_t,
            c_t,
            f0,
            k_c,
            c_c,
            arm,
            (fric_l, fric_r),
            (dof_l, dof_r),
            crr,
            r0,
        ) = self._fast
        qpos, qvel = qpos_v.tolist(), qvel_v.tolist()
        loads = self._loads
        load = k_t * qpos[qa] + c_t * qvel[va]
        loads[0] = load if load > 0.0 else 0.0
        load = k_t * qpos[qb] + c_t * qvel[vb]
        loads[1] = load if load > 0.0 else 0.0
        contact = None
        i = 2
        for qa, va in casters:
            q = qpos[qa]
            if q > 1e-6:  # off its stop: the spring carries the load
                load = f0 + k_c * q + c_c * qvel[va]
                loads[i] = load if load > 0.0 else 0.0
            else:  # on its stop (or lifted): the contact force tells
                if contact is None:
                    contact = self.physics.support.normal_forces_n().tolist()  # as rr_contact_loads
                loads[i] = contact[i]
            i += 1
        fl[dof_l] = fric_l + arm * loads[0]
        fl[dof_r] = fric_r + arm * loads[1]
        if crr == 0.0:
            return
        # ball velocity over the floor: the base's (world) velocity plus its yaw rate
        # (world z of the body-frame angular velocity) times the ball's lever arm
        vx, vy = qvel[r0], qvel[r0 + 1]
        _, _, _, _, _, _, x6, x7, x8 = xmat_base.tolist()
        wz = x6 * qvel[r0 + 3] + x7 * qvel[r0 + 4] + x8 * qvel[r0 + 5]
        xpos = xpos_v.tolist()
        bx, by, _ = xpos[base]
        fx = fy = tz = 0.0
        sqrt, eps = math.sqrt, BALL_SPEED_EPS_M_S
        i = 2
        for body in balls:
            px, py, _ = xpos[body]
            rx, ry = px - bx, py - by  # contact point, on the floor under the ball
            ux, uy = vx - wz * ry, vy + wz * rx
            speed = sqrt(
                ux * ux + uy * uy
            )  # as the C helper (libm's hypot and Python's differ in the last bit)
            scale = crr * loads[i] / (eps if eps > speed else speed)  # max(speed, eps)
            fx_i, fy_i = -scale * ux, -scale * uy
            fx, fy, tz = fx + fx_i, fy + fy_i, tz + rx * fy_i - ry * fx_i
            i += 1
        # the free joint's generalized force: world force, then the moment in the body frame
        # (R^T (0, 0, tz): the third column of the rotation's transpose is its third row)
        qfrc[r0 : r0 + 6] = (fx, fy, 0.0, x6 * tz, x7 * tz, x8 * tz)
