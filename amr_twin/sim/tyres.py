"""The drive tyres on the floor: a brush model with relaxation, applied every physics step.

Reasons and measurements: docs/explanation/tyres.md#amr_twinsimtyres.

Part of the physics layer (``PHYSICS_LAYER``): a MuJoCo passive callback: reads MjData and adds the
tyres' forces to ``qfrc_passive`` inside ``mj_step``."""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

from amr_twin.model.robot_starts import ROBOT_PREFIX
from amr_twin.model.tyre_numeric import (
    FIELD_CELLS,
    FIELD_OFFSET,
    FORMAT,
    NUMERIC_FIELDS,
    STATE_FIELDS,
    numeric_ids,
    numeric_name,
)
from amr_twin.sim.floor_friction import friction_at
from amr_twin.base.native_build import mujoco_address, open_helper

PHYSICS_LAYER = True

C_SOURCE = Path(__file__).with_name("tyres.c")
# [engine, helper, (global pointer, bindings' callback)]: what this process set
_installed: list = []


def install(native: bool | None = None) -> str:
    """Set the tyre callback as MuJoCo's ``mjcb_passive``; returns the engine, ``"C"`` or
    ``"Python (<why>)"``. ``native=None`` keeps what this process installed (the C helper when
    none was), ``False`` switches to the Python twin, ``True`` back. Raises RuntimeError when
    another library's passive callback is set.

    The C helper's address is written into libmujoco's ``mjcb_passive`` itself: set through the
    bindings, every step would pass through their trampoline (~0.7 us, 5 % of a step). The
    Python twin goes through the bindings (it is a Python function)."""
    import ctypes

    import mujoco

    slot = ctypes.c_void_p.from_address(mujoco_address("mjcb_passive"))
    if native is None:
        native = not _installed or _installed[1] is not None
    lib, engine = open_helper(C_SOURCE, native)
    if (
        _installed
        and _installed[0] == engine
        and _installed[2] == (slot.value, mujoco.get_mjcb_passive())
    ):
        return engine
    ours = _installed and _installed[2] == (slot.value, mujoco.get_mjcb_passive())
    if not ours and (slot.value or mujoco.get_mjcb_passive() is not None):
        raise RuntimeError(
            "tyres: MuJoCo's mjcb_passive is already set by another library; the tyre model "
            "needs it (set wheel.tyre_slip=false for the rigid contact)"
        )
    mujoco.set_mjcb_passive(None)
    if lib is not None:
        slot.value = ctypes.cast(lib.tyres_passive, ctypes.c_void_p).value
    else:
        mujoco.set_mjcb_passive(tyre_forces)
    _installed[:] = [engine, lib, (slot.value, mujoco.get_mjcb_passive())]
    return engine


def engine() -> str | None:
    """What computes the tyre forces in this process: ``"C"``, ``"Python (...)"`` or None (not
    installed)."""
    return _installed[0] if _installed else None


@dataclass(frozen=True)
class WheelContact:
    """One tyre's last contact state: deflections (m, m, rad), forces in its own axes (N, forward
    and left of the wheel; spin moment N m about the vertical) and the load N."""

    u_m: float
    v_m: float
    psi_rad: float
    fx_n: float
    fy_n: float
    mz_nm: float
    load_n: float


def contacts(model, data, prefix: str = ROBOT_PREFIX) -> tuple[WheelContact, WheelContact] | None:
    """(left, right) :class:`WheelContact` of the robot named ``prefix...`` at the last
    ``mj_forward``; None for a model without its tyres."""
    import mujoco

    n = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_NUMERIC, numeric_name(prefix))
    if n < 0:
        return None
    start = int(model.numeric_data[int(model.numeric_adr[n]) + 1]) + 1
    size = len(STATE_FIELDS)
    values = data.userdata[start : start + 2 * size].tolist()
    return WheelContact(*values[:size]), WheelContact(*values[size:])


def _cross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def tyre_forces(m, d) -> None:
    """The Python twin of ``tyres_passive`` (tyres.c): the same operations in the same order.

    A MuJoCo passive callback ``(MjModel, MjData)``: adds every robot's tyre forces to
    ``d.qfrc_passive``."""
    for n in numeric_ids(m):
        _robot_tyres(m, d, int(m.numeric_adr[n]))


def _robot_tyres(m, d, adr: int) -> None:
    """One robot's tyres, from its numeric at ``numeric_data[adr]`` (``robot_tyres`` of tyres.c)."""
    p = m.numeric_data[adr : adr + len(NUMERIC_FIELDS)].tolist()
    if p[0] != FORMAT:
        return
    (
        _,
        ud,
        r0,
        base,
        mu,
        c_alpha,
        c_kappa,
        s_alpha,
        s_kappa,
        crown,
        loss,
        k_t,
        c_t,
        v0,
        *wheels,
    ) = p
    ud, r0, base = int(ud), int(r0), int(base)
    st = d.userdata
    t = float(d.time)
    dt = t - st[ud]
    if not dt > 0.0:
        dt = 0.0
    st[ud] = t
    qvel, qpos = d.qvel.tolist(), d.qpos
    xm = d.xmat[base].tolist()
    xb = d.xpos[base].tolist()
    wl = qvel[r0 + 3 : r0 + 6]
    w = (
        xm[0] * wl[0] + xm[1] * wl[1] + xm[2] * wl[2],
        xm[3] * wl[0] + xm[4] * wl[1] + xm[5] * wl[2],
        xm[6] * wl[0] + xm[7] * wl[1] + xm[8] * wl[2],
    )
    ft0 = ft1 = 0.0
    tau0 = tau1 = tau2 = 0.0
    qf = d.qfrc_passive
    size = len(STATE_FIELDS)
    at = ud + FIELD_OFFSET
    field = st[at : at + 2 + FIELD_CELLS**2].tolist() if st[at] > 0.0 else None
    for k in range(2):
        slide, hinge, geom = (int(v) for v in wheels[3 * k : 3 * k + 3])
        s0 = ud + 1 + size * k
        qs, vs, vh = int(m.jnt_qposadr[slide]), int(m.jnt_dofadr[slide]), int(m.jnt_dofadr[hinge])
        load = k_t * float(qpos[qs]) + c_t * qvel[vs]
        if not load > 0.0:
            st[s0 : s0 + size] = 0.0
            continue
        r = float(m.geom_size[geom, 0])
        anchor = d.xanchor[hinge].tolist()
        ah = d.xaxis[hinge].tolist()
        a_s = d.xaxis[slide].tolist()
        ex0, ex1 = ah[1], -ah[0]
        norm = math.sqrt(ex0 * ex0 + ex1 * ex1)
        ex0 = ex0 / norm
        ex1 = ex1 / norm
        ey0, ey1 = -ex1, ex0
        pc = (anchor[0], anchor[1], anchor[2] - r)
        mu_c = friction_at(field, pc[0], pc[1]) if field is not None else mu
        rh = (anchor[0] - xb[0], anchor[1] - xb[1], anchor[2] - xb[2])
        rc = (pc[0] - xb[0], pc[1] - xb[1], pc[2] - xb[2])
        dc = (0.0, 0.0, -r)
        wrh, wrc = _cross(w, rh), _cross(w, rc)
        qs_dot, qh_dot = qvel[vs], qvel[vh]
        ws = (qh_dot * ah[0], qh_dot * ah[1], qh_dot * ah[2])
        spin = _cross(ws, dc)
        vh0 = qvel[r0] + wrh[0] + qs_dot * a_s[0]
        vh1 = qvel[r0 + 1] + wrh[1] + qs_dot * a_s[1]
        vc0 = qvel[r0] + wrc[0] + qs_dot * a_s[0] + spin[0]
        vc1 = qvel[r0 + 1] + wrc[1] + qs_dot * a_s[1] + spin[1]
        vx = vh0 * ex0 + vh1 * ex1
        vsx = vc0 * ex0 + vc1 * ex1
        vsy = vc0 * ey0 + vc1 * ey1
        wz = w[2] + ws[2]
        speed = abs(vx)
        defl = load / k_t
        a = math.sqrt(2.0 * r * defl)
        b = math.sqrt(2.0 * crown * defl)
        kx, ky = c_kappa * load / s_kappa, c_alpha * load / s_alpha
        kpsi = c_kappa * load * b * b / (3.0 * s_kappa)
        sgn = vx / math.sqrt(vx * vx + v0 * v0)
        u0, v_0, psi0 = st[s0], st[s0 + 1], st[s0 + 2]
        du = -vsx - speed * u0 / s_kappa
        dv = -vsy + a / 3.0 * wz * sgn - speed * v_0 / s_alpha
        dpsi = -wz - speed * psi0 / s_kappa
        u, v, psi = u0 + dt * du, v_0 + dt * dv, psi0 + dt * dpsi
        lim = 3.0 * mu_c * load
        fx, fy = kx * u, ky * v
        lin = math.sqrt(fx * fx + fy * fy)
        if lin > lim:
            slide_f, back = mu_c * load / lin, lim / lin
            fx = fx * slide_f
            fy = fy * slide_f
            u = u * back
            v = v * back
        else:
            q = lin / lim
            scale = 1.0 - q + q * q / 3.0
            fx = (fx + loss * kx * du) * scale
            fy = (fy + loss * ky * dv) * scale
        mmax = 3.0 * math.pi / 16.0 * mu_c * load * math.sqrt(a * b)
        mz = kpsi * psi
        if abs(mz) > mmax:
            psi = psi * mmax / abs(mz)
            mz = kpsi * psi
        else:
            mz = mz + loss * kpsi * dpsi
        st[s0 : s0 + size] = (u, v, psi, fx, fy, mz, load)
        f = (fx * ex0 + fy * ey0, fx * ex1 + fy * ey1, 0.0)
        qf[vs] += a_s[0] * f[0] + a_s[1] * f[1]
        arm = _cross(dc, f)
        qf[vh] += ah[0] * arm[0] + ah[1] * arm[1] + ah[2] * (arm[2] + mz)
        mc = _cross(rc, f)
        ft0 += f[0]
        ft1 += f[1]
        tau0 += mc[0]
        tau1 += mc[1]
        tau2 += mc[2] + mz
    qf[r0] += ft0
    qf[r0 + 1] += ft1
    qf[r0 + 3] += xm[0] * tau0 + xm[3] * tau1 + xm[6] * tau2
    qf[r0 + 4] += xm[1] * tau0 + xm[4] * tau1 + xm[7] * tau2
    qf[r0 + 5] += xm[2] * tau0 + xm[5] * tau1 + xm[8] * tau2
