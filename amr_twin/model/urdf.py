"""The robot description: parameters -> xacro -> URDF, checked by yourdfpy and cached.

:func:`derived_params` flattens the parameter file into what the xacro reads (lengths m,
masses kg, inertias kg m^2 as the diagonal [ixx, iyy, izz], positions [x, y, z] m);
:func:`robot_urdf` runs xacro and yourdfpy once per :func:`urdf_fingerprint` and keeps the
result in this process and on disk (:func:`urdf_cache_dir`). The MjSpec stage that adds
what URDF cannot carry is :mod:`amr_twin.model.robot_spec`; the assembly in a world is
:mod:`amr_twin.model.build`.
"""

from __future__ import annotations

import contextlib
import hashlib
import io
import json
import signal
import tempfile
import threading
from pathlib import Path

import numpy as np

from amr_twin.model import mass
from amr_twin.model.config import TwinConfig
from amr_twin.base.disk_cache import cache_dir, read_entry, store
from amr_twin.model.paths import MODEL_DIR, ROOT

XACRO_FILE = MODEL_DIR / "amr.urdf.xacro"

CACHE_FORMAT = 1
"""Part of every cache key: raise it when what a cached URDF means changes."""
_urdf_memo: dict[str, str] = {}


class BuildError(RuntimeError):
    """The model could not be built; the message is one line."""


_params_memo: dict[tuple, dict] = {}


def derived_params(cfg: TwinConfig) -> dict:
    """The flat parameter set the xacro reads (geometry, inertias, limits): a new dict.

    Kept per configuration without its payload (which nothing here reads): a sweep's points
    differ by their payload only, and each builds its model (~2.5 ms of mass properties and
    conversions a call, against ~0.05 to look it up)."""
    key = tuple(getattr(cfg, name) for name in type(cfg).model_fields if name != "payload")
    kept = _params_memo.get(key)
    if kept is None:
        if len(_params_memo) > 64:
            _params_memo.clear()
        kept = _params_memo[key] = _derived_params(cfg)
    return {name: (list(v) if isinstance(v, list) else v) for name, v in kept.items()}


def _derived_params(cfg: TwinConfig) -> dict:
    c, w, k = cfg.chassis, cfg.wheel, cfg.caster
    p = {
        "chassis_length_m": c.length_m,
        "chassis_width_m": c.width_m,
        "floor_a_z_m": c.floor_a_z_m,
        "floor_b_z_m": c.floor_b_z_m,
        "floor_c_z_m": c.floor_c_z_m,
        "tube_outer_m": c.tube_outer_m,
        "sheet_thickness_m": c.sheet_thickness_m,
        "deck_thickness_m": cfg.deck.thickness_m,
        # the true geometry: the nominal radius and separation plus the tyres' errors
        # (wheel.*_error_*)
        "wheel_radius_m": w.radius_m,
        "wheel_width_m": w.width_m,
        "wheel_separation_m": w.separation_m + w.separation_error_m,
        "wheel_left_radius_m": w.radius_of("left"),
        "wheel_right_radius_m": w.radius_of("right"),
        "wheel_torque_limit_nm": max(
            m.ke_v_s_rad * m.current_limit_a for m in (cfg.motor_left, cfg.motor_right)
        ),
        "wheel_speed_limit_rad_s": cfg.battery.v_full_v
        / min(cfg.motor_left.ke_v_s_rad, cfg.motor_right.ke_v_s_rad),
        "caster_ball_diameter_m": k.ball_diameter_m,
        "caster_x_m": k.x_m,
        "caster_y_m": k.y_m,
        "caster_travel_m": k.travel_m,
        "caster_drop_m": k.drop_m,
        # what URDF can say of the MJCF's joint dynamics (<dynamics>, <limit>): set again on the
        # MjSpec (robot_spec)
        "wheel_left_damping": cfg.motor_left.damping_nm_s_rad,
        "wheel_left_friction": cfg.motor_left.friction_nm,
        "wheel_right_damping": cfg.motor_right.damping_nm_s_rad,
        "wheel_right_friction": cfg.motor_right.friction_nm,
        "caster_damping_n_s_m": k.damping_n_s_m,
        "caster_effort_n": k.preload_n + k.stiffness_n_m * k.travel_m,
        "uwb_tag_pos_m": list(cfg.uwb.tag_pos_m),
        "uwb_tag_size_m": list(cfg.uwb.tag_size_m),
    }
    for name, comp in cfg.components.items():
        p[f"{name}_size_m"] = list(comp.size_m)
        p[f"{name}_pos_m"] = list(comp.pos_m)
    sensors = mass.sensor_link_inertials(cfg)
    for prefix, inertial in (
        ("chassis", mass.chassis_inertial(cfg)),
        ("wheel", mass.wheel_inertial(cfg)),
        ("caster", mass.caster_inertial(cfg)),
        ("laser", sensors["laser"]),
        ("imu_link", sensors["imu_link"]),
        ("uwb_tag", sensors["uwb_tag"]),
    ):
        p[f"{prefix}_mass_kg"] = inertial.mass_kg
        p[f"{prefix}_com_m"] = [float(v) for v in inertial.com_m]
        p[f"{prefix}_inertia"] = [float(v) for v in inertial.diag()]
    return {
        key: (float(v) if isinstance(v, (int, float, np.floating)) else v) for key, v in p.items()
    }


def urdf_string(cfg: TwinConfig, xacro_file: Path = XACRO_FILE) -> str:
    """Run xacro on the robot description with the resolved parameters."""
    import xacro  # imported here: slow, and only needed to build
    import yaml

    with tempfile.NamedTemporaryFile("w", suffix=".yaml", delete=False) as fh:
        yaml.safe_dump(derived_params(cfg), fh)
        params_path = fh.name
    try:
        doc = xacro.process_file(str(xacro_file), mappings={"params": params_path})
    except Exception as exc:  # XacroException, XML parse errors, missing file
        first = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
        raise BuildError(f"xacro {xacro_file.name}: {first}") from None
    finally:
        Path(params_path).unlink(missing_ok=True)
    text = doc.toprettyxml(indent="  ")
    # xacro names its absolute source path in a header comment: keep the file portable
    source = Path(xacro_file).resolve()
    shown = source.relative_to(ROOT).as_posix() if source.is_relative_to(ROOT) else source.name
    return text.replace(str(xacro_file), shown).replace(str(source), shown)


def urdf_cache_dir() -> Path | None:
    """The URDF cache's folder (:data:`~amr_twin.base.disk_cache.CACHE_ENV`), or None when the disk
    cache is off."""
    return cache_dir("urdf")


def urdf_fingerprint(cfg: TwinConfig, xacro_file: Path = XACRO_FILE) -> str:
    """Key of the robot description: the xacro source and the parameters it reads (not the
    payload, the motors' electrics or anything else added on the MjSpec), sha256."""
    text = Path(xacro_file).read_text()
    digest = hashlib.sha256()
    builder = Path(__file__).read_bytes()  # this module makes the URDF from the xacro's output
    for part in (
        f"format {CACHE_FORMAT}",
        str(xacro_file),
        text,
        json.dumps(derived_params(cfg), sort_keys=True),
    ):
        digest.update(part.encode())
        digest.update(b"\0")
    digest.update(builder)
    return digest.hexdigest()[:32]


def robot_urdf(cfg: TwinConfig, xacro_file: Path = XACRO_FILE) -> str:
    """The robot's URDF (:func:`urdf_string`), validated (:func:`check_urdf`) once per fingerprint.

    Cached in this process and on disk (:func:`urdf_cache_dir`): a payload sweep or a
    second run of the same robot skips xacro (~45 ms) and yourdfpy (~20 ms, and its trimesh
    import, ~0.8 s). A cached file is written only after the check passed, by one rename.
    """
    try:
        key = urdf_fingerprint(cfg, xacro_file)
    except OSError as exc:
        raise BuildError(f"xacro {Path(xacro_file).name}: {exc.strerror or exc}") from None
    urdf = _urdf_memo.get(key)
    if urdf is not None:
        return urdf
    folder = urdf_cache_dir()
    path = folder / f"{key}.urdf" if folder is not None else None
    try:
        urdf = (read_entry(path) or b"").decode()
    except UnicodeDecodeError:
        urdf = None
    if not urdf:
        urdf = urdf_string(cfg, xacro_file)
        check_urdf(urdf)
        if path is not None:
            store(path, urdf.encode())
    _urdf_memo[key] = urdf
    return urdf


@contextlib.contextmanager
def _ctrl_c_held():
    """Ctrl-C (SIGINT) held back in this block and raised again after it, to the handler in place
    before (KeyboardInterrupt by default). trimesh, which yourdfpy imports, catches
    ``BaseException`` around its optional imports (PIL, ...): a Ctrl-C while they ran was swallowed
    (a command ran on to its end) or left a module replaced by trimesh's ExceptionWrapper (a
    TypeError later). A handler that only notes the signal, not a blocked mask: the native threads
    numpy's BLAS starts would take a signal the main thread blocks. Python's handlers are the main
    thread's: elsewhere nothing is held."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    caught: list[int] = []
    previous = signal.signal(signal.SIGINT, lambda signum, frame: caught.append(signum))
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, previous)
        if caught:
            signal.raise_signal(signal.SIGINT)


def check_urdf(urdf: str) -> None:
    """Load and validate the URDF with yourdfpy; raise BuildError if it is invalid (a Ctrl-C
    meanwhile raises KeyboardInterrupt after it: :func:`_ctrl_c_held`)."""
    with _ctrl_c_held():
        import yourdfpy

        try:
            robot = yourdfpy.URDF.load(io.StringIO(urdf), load_meshes=False, build_scene_graph=True)
        except Exception as exc:
            raise BuildError(f"URDF: {str(exc).splitlines()[0]}") from None
    if not robot.validate():
        raise BuildError("URDF: yourdfpy validation failed")
    if robot.base_link != "base_link":
        raise BuildError(f"URDF: root link is {robot.base_link!r}, expected 'base_link'")
