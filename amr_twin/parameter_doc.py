"""The parameter table of ``models/amr/README.md``, generated from the parameter file.

``python -m amr_twin.parameter_doc`` rewrites the README's table and mass summary
after a change of ``amr.yaml`` (a test fails when a parameter is missing from it).
"""

from __future__ import annotations

from . import mass
from .config import load_config, parameter_table
from .paths import MODEL_DIR

HEADER = "# AMR robot model (amr-twin)\n\nThe differential-drive warehouse AMR of the thesis (`../../../shared/seed`, ch. 2): an AISI304\ntube chassis with three floors, two BLDC hub-motor wheels on the mid-length axle, four\nspring-loaded ball casters at the deck corners, an RPLIDAR A1 on the front border of the\npayload floor and an Adafruit 9-DOF IMU on the second floor. Laid out after mujoco_menagerie.\n\n| file | what it is |\n|---|---|\n| `amr.yaml` | **the** parameter file: every value with unit and source (table below) |\n| `amr.urdf.xacro` | source of the geometry: links, joints, visuals, collision shapes, inertias from the parameters |\n| `amr.urdf` | generated URDF (checked with yourdfpy) |\n| `amr.xml` | generated robot MJCF (MjSpec): free joint, motors, caster springs, contact parameters, sensors, sites |\n| `scene.xml` | the robot in the default warehouse (`../worlds/warehouse.xml`) for MuJoCo's viewer |\n\n## Build steps\n\n```\namr-twin model --export-urdf models/amr/amr.urdf --export-mjcf models/amr/amr.xml\n```\n\n1. `amr.yaml` is loaded and validated (pydantic, frozen; unknown keys, wrong units, out-of-range\n   or NaN values are refused with a one-line error). Overrides: `--params mine.yaml`, `--set key=value`.\n2. Mass properties are computed with trimesh from the same parametric geometry\n   (`amr_twin/mass.py`): the frame's hollow tubes (outer box minus bore), the floor plates, each\n   component as a box, the hub-motor stators on the chassis and the rotors in the wheel links.\n3. xacro renders `amr.urdf.xacro` with the resolved parameters; yourdfpy loads and validates it.\n4. MuJoCo imports the URDF into an MjSpec (visuals kept, no link fusion) and the build adds what\n   URDF cannot carry: the free joint; ellipsoid wheel collision shapes (a cylinder loses contact\n   when spinning in place); frictionless caster balls (`priority=1`, `condim=1`) on vertical\n   slide joints with stiffness, damping and a preload (`springref` below the lower stop); the\n   motors as affine actuators (torque = Kt/R·v − Kt·Ke/R·ω, clipped at Kt·I_max: MuJoCo's\n   quasi-static DC motor, evaluated in C); IMU, laser and base sites and sensors; the payload\n   box; geom groups (0 world, 1 robot visual, 2 robot collision, 4 payload).\n5. The robot is attached to a world (`--world warehouse|empty|PATH`) and compiled. A test fails\n   when the committed `amr.urdf`/`amr.xml` differ from what the build makes.\n\n"


def _fmt(value) -> str:
    if isinstance(value, list):
        return "[" + ", ".join(f"{x:g}" for x in value) + "]"
    return f"{value:g}" if isinstance(value, float) else str(value)


def readme_text() -> str:
    """The README: header, mass summary and one table row per parameter."""
    cfg = load_config()
    rows = "\n".join(f"| `{k}` | {_fmt(v)} | {u} | {s.replace('|', '/')} |" for k, v, u, s in parameter_table())
    summary = (f"Chassis link from the estimate: {mass.chassis_inertial(cfg).mass_kg:.2f} kg (frame "
               f"{mass.frame_inertial(cfg).mass_kg:.2f} kg of AISI304 tube); whole robot "
               f"{mass.robot_mass_kg(cfg):.2f} kg without payload.\n")
    return (HEADER + summary + "\n## Parameters\n\n| key | value | unit | source |\n|---|---|---|---|\n"
            + rows + "\n")


if __name__ == "__main__":
    (MODEL_DIR / "README.md").write_text(readme_text())
