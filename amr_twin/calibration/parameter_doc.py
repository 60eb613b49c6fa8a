"""The parameter table of ``models/amr/README.md``, generated from the parameter file.

``python -m amr_twin.calibration.parameter_doc`` rewrites the README's table and mass summary
after a change of ``amr.yaml`` (a test fails when a parameter is missing from it).
"""

from __future__ import annotations

from amr_twin.model import mass
from amr_twin.model.config import load_config, parameter_table
from amr_twin.model.statics import solve
from amr_twin.model.statics_sensitivity import sensitivity
from amr_twin.model.paths import MODEL_DIR

HEADER = (
    "# AMR robot model (amr-twin)\n\nThe differential-drive warehouse AMR of the thesis "
    "(`../../../shared/seed`, ch. 2): an AISI304\ntube chassis with three floors, two BLDC "
    "hub-motor wheels on the mid-length axle, four\nspring-loaded ball casters at the deck "
    "corners, an RPLIDAR A1 on the front border of the\npayload floor and an Adafruit 9-DOF IMU "
    "on the second floor. Laid out after mujoco_menagerie.\n\n| file | what it is "
    "|\n|---|---|\n| `amr.yaml` | **the** parameter file: every value with unit and source "
    "(table below) |\n| `sources.md` | the reasoning behind the sources that are decisions or "
    "estimates (each `amr.yaml` source links its section) |\n| `amr.urdf.xacro` | source of the "
    "geometry: links, joints, visuals, collision shapes, inertias from the parameters |\n| "
    "`amr.urdf` | generated URDF (checked with yourdfpy) |\n| `amr.xml` | generated robot MJCF "
    "(MjSpec): free joint, motors, caster springs, contact parameters, sensors, sites |\n| "
    "`scene.xml` | the robot in the default warehouse (`../worlds/warehouse.xml`) for MuJoCo's "
    "viewer |\n\n## Build steps\n\n```\namr-twin model --export-urdf models/amr/amr.urdf "
    "--export-mjcf models/amr/amr.xml\n```\n\n1. `amr.yaml` is loaded and validated (pydantic, "
    "frozen; unknown keys, wrong units, out-of-range\n   or NaN values are refused with a "
    "one-line error). Overrides: `--params mine.yaml`, `--set key=value`.\n2. Mass properties "
    "are computed in closed form from the same parametric geometry\n   "
    "(`amr_twin/model/mass.py`, checked against trimesh in the tests): the frame's hollow tubes "
    "(outer\n   box minus bore), the floor plates, each component as a box, the hub-motor "
    "stators on the\n   chassis and the rotors in the wheel links (solid cylinders), the caster "
    "units (solid spheres).\n3. xacro renders `amr.urdf.xacro` with the resolved parameters; "
    "yourdfpy loads and validates it.\n4. MuJoCo imports the URDF into an MjSpec (visuals kept, "
    "no link fusion) and the build adds what\n   URDF cannot carry: the free joint; ellipsoid "
    "wheel collision shapes (a cylinder loses contact\n   when spinning in place); each tyre's "
    "radial compliance as a vertical slide between hub and\n   chassis (stiffness, damping); "
    "frictionless caster balls (`priority=1`, `condim=1`) on vertical\n   slide joints with "
    "stiffness, damping and a preload (`springref` below the lower stop); stiff\n   contacts for "
    "wheels and balls (solref 2 ms, solimp 0.97), so that the load split follows the\n   "
    "springs, not the solver; the motors as affine actuators (torque = Kt/R·v − Kt·Ke/R·ω, "
    "clipped\n   at Kt·I_max: MuJoCo's quasi-static DC motor, evaluated in C; a braked motor is "
    "the same\n   motor at zero phase voltage, its phases shorted); IMU, laser and base sites "
    "and sensors; the\n   payload box; geom groups (0 world, 1 robot visual, 2 robot collision, "
    "4 payload). The\n   tyres' and casters' rolling resistance, proportional to their loads, is "
    "applied while the\n   twin runs (`amr_twin/sim/rolling_resistance.py`).\n5. The robot is "
    "attached to a world (`--world warehouse|empty|PATH`) and compiled with MuJoCo's\n   "
    "constraint islands off (one robot: at most one island). A run nothing draws (no `--record`, "
    "no\n   live view) leaves the robot's visual geoms out (they collide with nothing and weigh "
    "nothing), and\n   one without `--sensors` the IMU's sensors: the same dynamics to the bit, "
    "cheaper steps. A test\n   fails when the committed `amr.urdf`/`amr.xml` differ from what "
    "the build makes. The exported\n   `amr.xml` carries the twin's `<option>` block (timestep, "
    "integrator, cone, flags), so it steps alone\n   in plain MuJoCo as the twin does.\n\n"
)


def _fmt(value) -> str:
    if isinstance(value, list):
        return "[" + ", ".join(f"{x:g}" for x in value) + "]"
    return f"{value:g}" if isinstance(value, float) else str(value)


def readme_text() -> str:
    """The README: header, mass summary, statics, uncertainty and one table row per parameter."""
    from amr_twin.calibration.uncertainty import ParameterSpace

    cfg = load_config()
    space = ParameterSpace.load()
    rows = "\n".join(
        f"| `{k}` | {_fmt(v)} | {u} | {s.replace('|', '/')} | {_spread_cell(space, k)} |"
        for k, v, u, s in parameter_table()
    )
    summary = (
        f"Chassis link from the estimate: {mass.chassis_inertial(cfg).mass_kg:.2f} kg (frame "
        f"{mass.frame_inertial(cfg).mass_kg:.2f} kg of AISI304 tube); whole robot "
        f"{mass.robot_mass_kg(cfg):.2f} kg without payload.\n"
    )
    return (
        HEADER
        + summary
        + _statics_text(cfg)
        + _uncertainty_text(space)
        + "\n## Parameters\n\n| key | value | unit | source | spread (`--samples`) "
        "|\n|---|---|---|---|---|\n" + rows + "\n"
    )


def _spread_cell(space, key: str) -> str:
    s = space.spreads[key]
    if s.kind == "calibrated":
        rep = space.calibration
        i = rep.keys.index(key)
        j = max(
            (j for j in range(len(rep.keys)) if j != i), key=lambda j: abs(rep.correlation[i, j])
        )
        return (
            f"σ {s.sigma[0]:.3g}, jointly with the fit (r {rep.correlation[i, j]:+.3f} with "
            f"`{rep.keys[j]}`; `calibration.yaml`)"
        )
    return f"{s.describe()}: {s.reason}".replace("|", "/")


def _uncertainty_text(space) -> str:
    """How each parameter's spread is set, and the calibration's correlations."""
    from amr_twin.model.parameter_spreads import DEFAULT_TOLERANCE

    rep = space.calibration
    head = (
        "| | "
        + " | ".join(f"`{k}`" for k in rep.keys)
        + " |\n|---|"
        + "---|" * len(rep.keys)
        + "\n"
    )
    corr = "".join(
        f"| `{k}` (σ {s:.3g}) | " + " | ".join(f"{c:+.3f}" for c in row) + " |\n"
        for k, s, row in zip(rep.keys, rep.sigma, rep.correlation)
    )
    held = ", ".join(f"`{k}`" for k in rep.held_keys)
    defaults = ", ".join(f"{kind} ±{tol:.0%}" for kind, tol in DEFAULT_TOLERANCE.items())
    return (
        "\n## Uncertainty\n\n`--samples N` (`amr-twin sweep payload`, `amr-twin experiment "
        "chapter5`) draws the "
        "robot's body and drive\nparameters from the spreads in the table below "
        "(`amr_twin/calibration/uncertainty.py`): a "
        "leaf's `range: [lo, hi]`\n(uniform), `sigma` (normal) or `follows` (the same relative "
        "deviation as "
        "another parameter), each\nwith its `reason`; without one, the source's kind sets it "
        "(uniform, "
        f"{defaults}; a vector, a zero or an\ninteger stays exact). Settings (time step, "
        f"payload, sensor modes, "
        "estimator tuning) are never drawn.\n\nThe calibrated parameters are drawn jointly from "
        "the calibration's "
        f"report (`calibration.yaml`, {rep.target},\nchi^2 {rep.chi2:.1f}; written by `amr-twin "
        f"calibrate --no-fit "
        "--report models/amr/calibration.yaml`):\n\n"
        + head
        + corr
        + f"\nand each draw is shifted by how the fit follows the parameters it held: {held}\n"
        "(`follow` in `calibration.yaml`; e.g. a damper 0.004 N m s/rad stronger takes 0.03 N m "
        "off the dry "
        "friction,\nsince the bench point pins their sum), so that every drawn plant still fits "
        "the thesis.\n"
    )


def _statics_text(cfg) -> str:
    """Static loads (``amr-twin model --json``) and their sensitivity to the caster set-up."""
    st = solve(cfg)
    loads = ", ".join(f"{k} {v:.1f} N" for k, v in st.loads_n.items())
    rows = "\n".join(
        f"| {r['case']} | {r['variant']} | {r['wheel_left']:.1f} | {r['caster_front_left']:.1f} | "
        f"{r['caster_rear_left']:.1f} | {', '.join(r['lifted']) or '-'} |"
        for r in sensitivity(cfg)
    )
    return (
        "\n## Static loads\n\nFrom the springs that carry them (`amr_twin/model/statics.py`, a "
        "hand calculation that "
        "a test checks against\na free settle of `amr.xml` on a plane): tyres of radial stiffness "
        "`wheel.tyre_stiffness_n_m`, casters\nwith their preload and spring, whose balls at the "
        "lower stop reach "
        "`caster.drop_m` below the unloaded\ntyres. Without payload: " + loads + ".\n\n"
        "The chassis stands on six supports, so the split depends on millimetres: a tyre 2 mm "
        "larger\n"
        "on the same chassis lifts the casters by 2 mm. Sensitivity (left side; the right "
        "mirrors it):\n\n"
        "| case | variant | wheel N | front caster N | rear caster N | lifted "
        "|\n|---|---|---|---|---|---|\n" + rows + "\n"
    )


if __name__ == "__main__":
    (MODEL_DIR / "README.md").write_text(readme_text())
