"""Where the tyre model's parameters live in a compiled model: one numeric per robot, and the
state's user data.

The model build (:func:`amr_twin.model.build.build`) adds, per robot, the numeric
:func:`numeric_name` (:data:`NUMERIC` for the lone robot) with the
values of :data:`NUMERIC_FIELDS` (the parameters from ``wheel.*``, then the ids of the joints,
geoms and bodies the tyre callback reads, written after compiling by :func:`set_addresses`) and
:data:`USERDATA_SIZE` values of ``d.userdata`` for the deflection states and the floor's friction
field (:data:`FIELD_OFFSET`). The callback that uses
them is :mod:`amr_twin.sim.tyres` (and its C twin ``tyres.c``, whose enums follow this layout).
"""

from __future__ import annotations

from amr_twin.model.robot_starts import ROBOT_PREFIX

NUMERIC = "amr_tyres"
"""Name of the lone robot's numeric holding the tyre parameters and addresses; a fleet robot's is
``amr_tyres:<prefix>`` (:func:`numeric_name`)."""
FORMAT = 1.0
NUMERIC_FIELDS = (
    "format",
    "userdata",
    "root_dof",
    "base",
    "mu",
    "c_alpha",
    "c_kappa",
    "sigma_alpha",
    "sigma_kappa",
    "crown",
    "loss",
    "k_t",
    "c_t",
    "v_sign",
    "slide_l",
    "hinge_l",
    "geom_l",
    "slide_r",
    "hinge_r",
    "geom_r",
)
"""The numeric's values, in order (tyres.c's enums)."""
STATE_FIELDS = ("u_m", "v_m", "psi_rad", "fx_n", "fy_n", "mz_nm", "load_n")
"""Per wheel in ``d.userdata`` after the time stamp: deflections (state), then the last output."""
FIELD_CELLS = 32
"""Nodes of the floor's friction field along x and along y (periodic: it repeats every 32
patches)."""
FIELD_OFFSET = 1 + 2 * len(STATE_FIELDS)
"""Where the friction field starts in the tyres' user data: node count (0: no field, the numeric's
``mu`` everywhere), node spacing (m), then the (FIELD_CELLS, FIELD_CELLS) friction coefficients,
row y, column x (:mod:`amr_twin.sim.floor_friction`)."""
USERDATA_SIZE = FIELD_OFFSET + 2 + FIELD_CELLS * FIELD_CELLS
V_SIGN_M_S = 0.01
"""Rolling speed over which the direction of rolling is smoothed, m/s (turn slip's sign)."""


def numeric_values(cfg, userdata_adr: int = 0) -> list[float]:
    """The numeric :data:`NUMERIC` of ``cfg``'s tyres; the addresses are 0 until
    :func:`set_addresses`."""
    w = cfg.wheel
    values = dict(
        format=FORMAT,
        userdata=float(userdata_adr),
        mu=w.friction,
        c_alpha=w.cornering_stiffness_per_n,
        c_kappa=w.slip_stiffness_per_n,
        sigma_alpha=w.relaxation_length_lateral_m,
        sigma_kappa=w.relaxation_length_longitudinal_m,
        crown=w.tyre_crown_radius_m,
        loss=w.tyre_loss_time_s,
        k_t=w.tyre_stiffness_n_m,
        c_t=w.tyre_damping_n_s_m,
        v_sign=V_SIGN_M_S,
    )
    return [float(values.get(name, 0.0)) for name in NUMERIC_FIELDS]


def numeric_name(prefix: str) -> str:
    """The tyres' numeric of the robot whose names begin with ``prefix``."""
    return NUMERIC if prefix == ROBOT_PREFIX else f"{NUMERIC}:{prefix}"


def numeric_ids(model) -> list[int]:
    """The ids of every robot's tyre numeric in ``model``, in id order (tyres.c walks the same)."""
    names = [model.numeric(i).name for i in range(model.nnumeric)]
    return [i for i, name in enumerate(names) if name.split(":")[0] == NUMERIC]


def set_addresses(model, prefix: str) -> None:
    """Write the ids the callback needs (joints, geoms, bodies of the robot named ``prefix...``)
    into the compiled ``model``'s numeric."""
    import mujoco

    def get(kind, name):
        i = mujoco.mj_name2id(model, kind, prefix + name)
        if i < 0:
            raise KeyError(f"tyres: the model has no {prefix + name}")
        return i

    J, G, B = mujoco.mjtObj.mjOBJ_JOINT, mujoco.mjtObj.mjOBJ_GEOM, mujoco.mjtObj.mjOBJ_BODY
    ids = {"root_dof": model.jnt_dofadr[get(J, "root")], "base": get(B, "base_link")}
    for side, s in (("left", "l"), ("right", "r")):
        ids[f"slide_{s}"] = get(J, f"wheel_{side}_tyre")
        ids[f"hinge_{s}"] = get(J, f"wheel_{side}_joint")
        ids[f"geom_{s}"] = get(G, f"wheel_{side}_collision")
    n = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_NUMERIC, numeric_name(prefix))
    adr = int(model.numeric_adr[n])
    for name, value in ids.items():
        model.numeric_data[adr + NUMERIC_FIELDS.index(name)] = float(value)
