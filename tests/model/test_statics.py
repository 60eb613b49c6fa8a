"""Static loads from the tyres' and casters' springs: a hand figure, a free settle of the
exported MJCF in MuJoCo, payload shifts, the sensitivity to the caster set-up, tip margin."""

import mujoco
import numpy as np
import pytest

from amr_twin.model.build import export
from amr_twin.model.config import load_config
from amr_twin.model.statics import describe, solve

G = 9.81
BALL_KG = 0.15


def _mujoco_mass_kg(cfg) -> float:
    """The robot's mass as MuJoCo sums its bodies (not amr_twin.model.mass)."""
    m = mujoco.MjModel.from_xml_path(str(_export(cfg)))
    return float(m.body_subtreemass[m.body("base_link").id])


_EXPORTS = {}


def _exported(cfg):
    """The robot MJCF exported for ``cfg`` (a path) and the twin's model it came from."""
    key = cfg.model_dump_json()
    if key not in _EXPORTS:
        import tempfile
        from pathlib import Path

        path = Path(tempfile.mkdtemp()) / "amr.xml"
        _EXPORTS[key] = path, export(cfg, mjcf_path=path).model
    return _EXPORTS[key]


def _export(cfg):
    return _exported(cfg)[0]


@pytest.mark.parametrize("payload", [[], ["payload.mass_kg=20"]])
def test_wheel_load_matches_the_hand_figure(payload):
    """All six supports sprung, casters flush with the unloaded tyres (drop 0): the tyres and
    the caster springs compress by the same sink u at the axle on average (casters at +-x
    cancel the pitch), so 2 k_t u + 4 (P + m_ball g + k_c u) = W and each wheel carries k_t u."""
    cfg = load_config(sets=payload)
    k_t, k_c, p = cfg.wheel.tyre_stiffness_n_m, cfg.caster.stiffness_n_m, cfg.caster.preload_n
    assert cfg.caster.drop_m == 0.0 and cfg.caster.mass_kg == BALL_KG
    weight = _mujoco_mass_kg(cfg) * G
    u = (weight - 4 * (p + BALL_KG * G)) / (2 * k_t + 4 * k_c)
    st = solve(cfg)
    assert set(st.regimes.values()) == {"sprung"}
    for wheel in ("wheel_left", "wheel_right"):
        assert st.loads_n[wheel] == pytest.approx(k_t * u, rel=1e-3)
    assert sum(st.loads_n.values()) == pytest.approx(weight, rel=1e-6)


SUPPORT_GEOMS = {
    "wheel_left": "wheel_left_collision",
    "wheel_right": "wheel_right_collision",
    **{
        f"caster_{c}": f"caster_{c}_ball"
        for c in ("front_left", "front_right", "rear_left", "rear_right")
    },
}


def _vertical_forces_n(m, d) -> dict:
    """Each support's vertical contact force with the floor, N (summed over its contacts)."""
    ids = {key: m.geom(geom).id for key, geom in SUPPORT_GEOMS.items()}
    force, loads = np.zeros(6), dict.fromkeys(ids, 0.0)
    for i in range(d.ncon):
        contact = d.contact[i]
        mujoco.mj_contactForce(m, d, i, force)
        vertical = abs((contact.frame.reshape(3, 3).T @ force[:3])[2])
        for key, geom in ids.items():
            if geom in (contact.geom1, contact.geom2):
                loads[key] += vertical
    return loads


@pytest.mark.parametrize(
    "payload",
    [
        [],
        ["payload.mass_kg=20", "payload.xy_m=[-0.2,0.0]"],
        ["payload.mass_kg=40", "payload.xy_m=[0.1,0.05]"],
    ],
)
def test_exported_mjcf_settled_on_a_plane_agrees_within_one_percent(payload):
    """The exported robot MJCF as written (its own <option>, only a floor plane added: the export
    has none), settled for 2 s in plain MuJoCo, carries each support's vertical load within 1 % of
    ``amr-twin model --json`` (:func:`describe`) over the last 0.1 s; its options are the twin's."""
    cfg = load_config(sets=payload)
    info = describe(cfg)
    path, twin = _exported(cfg)
    spec = mujoco.MjSpec.from_file(str(path))
    assert not [g for g in spec.geoms if g.type == mujoco.mjtGeom.mjGEOM_PLANE]
    spec.worldbody.add_geom(name="floor", type=mujoco.mjtGeom.mjGEOM_PLANE, size=[5, 5, 0.1])
    m = spec.compile()
    for name in (
        "timestep",
        "integrator",
        "cone",
        "solver",
        "iterations",
        "noslip_iterations",
        "disableflags",
        "enableflags",
    ):
        assert getattr(m.opt, name) == getattr(twin.opt, name), name
    d = mujoco.MjData(m)
    steps, tail = round(2.0 / m.opt.timestep), round(0.1 / m.opt.timestep)
    mujoco.mj_step(m, d, steps - tail)  # motors at 0 V: their phases short, the robot comes to rest
    assert set(info["support_regime"].values()) == {
        "sprung"
    }  # every load set by springs, none by a stop
    for _ in range(tail):
        mujoco.mj_step(m, d)
        settled = _vertical_forces_n(m, d)
        for key, load in info["static_load_n"].items():
            assert settled[key] == pytest.approx(load, rel=0.01), (key, d.time)
    assert np.abs(d.qvel).max() < 1e-3


def test_payload_at_front_loads_front_casters():
    front = describe(load_config(sets=["payload.mass_kg=20", "payload.xy_m=[0.18,0.0]"]))
    loads = front["static_load_n"]
    assert loads["caster_front_left"] > loads["caster_rear_left"] + 20
    assert front["com_m"][0] > 0.05


def test_caster_set_up_moves_the_load_between_wheels_and_casters():
    """Casters 2 mm higher (a 2 mm larger tyre) unload them: with 20 kg at the rear edge the
    front balls leave the floor; softer caster springs give the wheels more."""
    rear = ["payload.mass_kg=20", "payload.xy_m=[-0.2,0.0]"]
    nominal = solve(load_config(sets=rear))
    higher = solve(load_config(sets=rear + ["caster.drop_m=-0.002"]))
    softer = solve(load_config(sets=rear + ["caster.stiffness_n_m=14000"]))
    assert higher.loads_n["caster_front_left"] == 0.0 < nominal.loads_n["caster_front_left"]
    assert higher.loads_n["wheel_left"] > nominal.loads_n["wheel_left"] + 30
    assert softer.loads_n["wheel_left"] > nominal.loads_n["wheel_left"] + 10


def test_unloaded_tip_margin_is_the_distance_to_the_wheel_caster_edge():
    """All supports on the floor: the nearest edge of the hexagon is the line from a rear
    caster (-0.30, 0.17) to a wheel (0, 0.24); the centre of mass sits a few mm behind the axle."""
    info = describe(load_config())
    (x, y), (a, b), (c, d) = info["com_m"][:2], (-0.30, 0.17), (0.0, 0.24)
    hand = abs((c - a) * (y - b) - (d - b) * (x - a)) / np.hypot(c - a, d - b)
    assert info["tip_margin_m"] == pytest.approx(hand, abs=1e-4)
    assert 0.2 < hand < 0.25


def test_a_solution_asked_again_is_the_kept_one_and_the_callers_own(monkeypatch):
    """solve: the same robot and acceleration are solved once while among the last
    SOLVED_KEPT asked; another payload or acceleration is solved anew; a caller's edits of
    its result change nothing kept."""
    import amr_twin.model.statics as statics

    monkeypatch.setattr(statics, "_solved", {})
    calls = []
    real = statics._solve
    monkeypatch.setattr(
        statics, "_solve", lambda cfg, a: (calls.append((cfg.payload.mass_kg, a)), real(cfg, a))[1]
    )
    cfg, heavy = load_config(), load_config(sets=["payload.mass_kg=30"])
    first = solve(cfg)
    wheel = first.loads_n["wheel_left"]
    first.loads_n["wheel_left"] = -1.0
    first.com_m[0] = 9.0
    again = solve(cfg, (0.0, 0.0))
    assert again.loads_n["wheel_left"] == wheel and again.com_m[0] != 9.0 and len(calls) == 1
    assert solve(heavy).loads_n["wheel_left"] > wheel and len(calls) == 2
    turning = solve(cfg, (0.0, 2.0))
    assert turning.loads_n["wheel_left"] != wheel and len(calls) == 3
    for i in range(statics.SOLVED_KEPT - 1):  # the robot at rest stays among the last asked...
        solve(cfg, (0.01 * (i + 1), 0.0))
        solve(cfg)
    assert len(calls) == 3 + statics.SOLVED_KEPT - 1
    for i in range(statics.SOLVED_KEPT):  # ... until SOLVED_KEPT others were asked after it
        solve(heavy, (0.0, 0.01 * (i + 1)))
    solve(cfg)
    assert len(calls) == 3 + 2 * statics.SOLVED_KEPT
