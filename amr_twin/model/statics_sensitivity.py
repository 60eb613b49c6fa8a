"""How the hand statics' support loads move with the wheel radius and the caster springs, unloaded
and with 20 kg at the deck's rear edge (:func:`sensitivity`, the table of the parameter file's
README)."""

from __future__ import annotations

from amr_twin.model.config import TwinConfig
from amr_twin.model.statics import LIFTED, solve

SENSITIVITY_CASES = (
    ("no payload", {}),
    ("20 kg at the deck's rear edge", {"payload.mass_kg": 20.0, "payload.xy_m": [-0.2, 0.0]}),
)
SENSITIVITY_VARIANTS = (
    ("as in amr.yaml", {}),
    ("wheel radius +2 mm (same chassis: casters 2 mm higher)", {"caster.drop_m": -0.002}),
    ("wheel radius -2 mm (casters 2 mm lower)", {"caster.drop_m": 0.002}),
    ("caster springs -30 %", {"caster.stiffness_n_m": 0.7}),
    ("caster springs +30 %", {"caster.stiffness_n_m": 1.3}),
)


def sensitivity(cfg: TwinConfig) -> list[dict]:
    """Static loads for :data:`SENSITIVITY_CASES` x :data:`SENSITIVITY_VARIANTS`.

    A larger tyre on the same chassis lifts the casters' mounts: its radius change is
    taken as the opposite change of ``caster.drop_m`` (``base_link`` stays on the floor).
    Spring variants scale the stiffness. Returns one dict per case and variant: the
    loads (N) of the left wheel and the left front and rear casters, and the regimes.
    """
    rows = []
    for case, payload in SENSITIVITY_CASES:
        for variant, change in SENSITIVITY_VARIANTS:
            data = cfg.model_dump()
            for key, value in {**payload, **change}.items():
                section, name = key.split(".")
                base = data[section][name]
                data[section][name] = (
                    base + value
                    if key == "caster.drop_m"
                    else base * value
                    if key == "caster.stiffness_n_m"
                    else value
                )
            st = solve(TwinConfig.model_validate(data))
            rows.append(
                {
                    "case": case,
                    "variant": variant,
                    **{
                        k: st.loads_n[k]
                        for k in ("wheel_left", "caster_front_left", "caster_rear_left")
                    },
                    "lifted": [k for k, r in st.regimes.items() if r == LIFTED],
                }
            )
    return rows
