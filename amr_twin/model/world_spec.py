"""A world for the model build: its file checked (``--world``: a world of ``models/worlds/``, an
MJCF file, a map_server map, a generated hall), its MjSpec with the simulation's options, and the
world alone compiled (:func:`world_model`)."""

from __future__ import annotations

from pathlib import Path

import mujoco

from amr_twin.model.config import TwinConfig
from amr_twin.model.robot_spec import GROUP_WORLD
from amr_twin.model.urdf import BuildError
from amr_twin.model.worlds import WORLD_DIR


def world_file(world: str | Path) -> Path:
    """The file of ``--world``: a world of ``models/worlds/``, an MJCF world (``.xml``) or a
    map_server map (``.yaml``); anything else, a URDF above all (MuJoCo would load it as a world
    with no floor), is a
    :class:`BuildError` saying what is allowed. ``generated:SEED[?door=W]``: a drawn hall
    (:mod:`amr_twin.model.generated_world`)."""
    from amr_twin.model.generated_world import is_generated, world_file as generated_file

    if is_generated(world):
        try:
            return generated_file(str(world))
        except ValueError as exc:
            raise BuildError(str(exc)) from None
    path = Path(world)
    if not path.suffix:
        path = WORLD_DIR / f"{world}.xml"
    names = ", ".join(sorted(p.stem for p in WORLD_DIR.glob("*.xml")))
    if not path.exists():
        raise BuildError(f"--world {world}: no such world (available: {names})")
    suffix = path.suffix.lower()
    urdf = suffix == ".urdf" or (suffix == ".xml" and _root_tag(path) == "robot")
    if urdf or suffix not in (".xml", ".yaml", ".yml"):
        what = "a URDF describes a robot, not a world" if urdf else "not a world file"
        raise BuildError(
            f"--world {world}: {what}: give a world ({names}), an MJCF world file (.xml) or a "
            "map_server map (.yaml)"
        )
    return path


def _root_tag(path: Path) -> str | None:
    """The root element's tag of an XML file (``robot``: a URDF, ``mujoco``: MJCF); None if not
    XML."""
    import xml.etree.ElementTree as ET

    try:
        for _event, element in ET.iterparse(str(path), events=("start",)):
            return element.tag
    except (ET.ParseError, OSError, UnicodeError):
        return None
    return None


def world_compile_error(world: str | Path, exc: Exception) -> BuildError:
    """MuJoCo's error compiling the world ``world``, naming its file (MuJoCo's text names
    neither)."""
    first = " ".join(str(exc).split())[:200] or type(exc).__name__
    return BuildError(f"--world {world}: MuJoCo compile: {first}")


def world_spec(cfg: TwinConfig, world: str | Path) -> mujoco.MjSpec:
    """The MjSpec of ``world`` (:func:`world_file`; a map's walls extruded), with the simulation
    options of ``cfg`` (timestep, integrator, gravity, floor friction) and its geoms in the world's
    group. Raises :class:`~amr_twin.model.urdf.BuildError`."""
    path = world_file(world)
    if path.suffix in (".yaml", ".yml"):  # a ROS map_server map: walls extruded from the image
        from amr_twin.model.occupancy_map import world_xml

        spec = mujoco.MjSpec.from_string(world_xml(path))
    else:
        try:
            spec = mujoco.MjSpec.from_file(str(path))
        except Exception as exc:  # XML parse errors name neither the file nor the problem's context
            first = " ".join(str(exc).split())[:200] or type(exc).__name__
            raise BuildError(f"--world {path}: not a valid MJCF world ({first})") from None
    spec.option.timestep = cfg.sim.timestep_s
    spec.option.integrator = mujoco.mjtIntegrator.mjINT_IMPLICITFAST
    spec.option.cone = mujoco.mjtCone.mjCONE_ELLIPTIC  # see robot_spec.robot_spec
    # Island discovery off: ~2 us a step for nothing with one robot (one tree, one island), no
    # gain measured with eight (docs/explanation/architecture.md#several-robots-in-one-model).
    spec.option.disableflags |= mujoco.mjtDisableBit.mjDSBL_ISLAND
    spec.option.gravity = [0.0, 0.0, -cfg.sim.gravity_m_s2]
    # ~48 uT, northern-Italy inclination (WMM estimate)
    spec.option.magnetic = [0.0, 2.2e-5, -4.3e-5]
    for geom in spec.geoms:
        geom.group = GROUP_WORLD
        if geom.type == mujoco.mjtGeom.mjGEOM_PLANE:
            geom.friction = [cfg.sim.floor_friction, 0.005, 0.0001]
    return spec


def world_model(cfg: TwinConfig, world: str | Path) -> mujoco.MjModel:
    """The world alone, compiled (no robot): where actors may walk
    (:mod:`amr_twin.model.actor_space`), where a route may go
    (:func:`amr_twin.experiments.fusion.experiment.check_route`)."""
    try:
        return world_spec(cfg, world).compile()
    except BuildError:
        raise
    except Exception as exc:
        raise world_compile_error(world, exc) from None
