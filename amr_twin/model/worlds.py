"""The twin's worlds: where a world's file is (a name of ``models/worlds/``, a path, a generated
hall), the files it reads, and what an MJCF world declares in its ``<custom><numeric>`` elements
(start pose, UWB anchors, charging stations); the unmapped :class:`Obstacle` boxes added to one.
Occupancy maps as worlds: :mod:`amr_twin.model.occupancy_map`. This module does not import mujoco.
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from amr_twin.model.paths import ROOT

WORLD_DIR = ROOT / "models" / "worlds"
START_NUMERIC = "start_xy_yaw"
"""Name of an MJCF ``<custom><numeric>`` holding a world's default start pose: x_m y_m yaw_rad."""
ANCHORS_NUMERIC = "uwb_anchors_xy_m"
"""Name of an MJCF ``<custom><numeric>`` holding a world's UWB anchors: x0 y0 x1 y1 ... (m)."""
CHARGER_PREFIX = "charging_station:"
"""Prefix of the MJCF ``<custom><numeric>`` names declaring a world's charging stations: the name
after it is the station's, the data where a robot stands to charge: x_m y_m yaw_rad."""


def world_path(world: str | Path) -> Path:
    """The file of ``world``: a name of ``models/worlds/`` (``warehouse``, ``empty``), a path, or a
    generated hall ``generated:SEED[?door=W]`` (:mod:`amr_twin.model.generated_world`, written on
    first use)."""
    from amr_twin.model.generated_world import is_generated, world_file

    if is_generated(world):
        return world_file(str(world))
    path = Path(world)
    return WORLD_DIR / f"{world}.xml" if not path.suffix else path


def world_files(world: str | Path) -> list[Path]:
    """The files ``world`` reads: its MJCF file, or a map YAML and the image it names (when it names
    one)."""
    try:
        path = world_path(world)
    except ValueError:  # a bad generated:SEED name: the model build says why
        return []
    if path.suffix.lower() not in (".yaml", ".yml"):
        return [path]
    from amr_twin.model.yaml_file import read_yaml

    try:
        image = read_yaml(path, "map", MapError).get("image")
    except (MapError, AttributeError):  # unreadable: the model build says why
        return [path]
    return [path] + ([path.parent / image] if isinstance(image, str) and image.strip() else [])


def _numerics(world: str | Path) -> dict[str, list[float] | None]:
    """The MJCF ``<custom><numeric>`` values of ``world`` by name (None: not numbers); empty for a
    map or an unreadable file."""
    path = world_path(world)
    if path.suffix.lower() != ".xml":
        return {}
    try:
        root = ET.parse(path).getroot()
    except (OSError, ET.ParseError):
        return {}
    out: dict[str, list[float] | None] = {}
    for numeric in root.iter("numeric"):
        try:
            values = [float(v) for v in (numeric.get("data") or "").split()]
        except ValueError:
            values = None
        out.setdefault(numeric.get("name") or "", values)
    return out


def _numeric(world: str | Path, name: str) -> list[float] | None:
    """Values of the MJCF ``<custom><numeric name=NAME>`` of ``world``; None if absent or
    unreadable."""
    return _numerics(world).get(name)


def default_start(world: str | Path) -> tuple[float, float, float]:
    """The world's start pose ``(x_m, y_m, yaw_rad)``: its ``start_xy_yaw`` numeric, else the
    origin.

    Only MJCF worlds can declare one (``<custom><numeric name="start_xy_yaw" data="x y yaw"/>``);
    a file that cannot be read gives the origin (the model build reports the error).
    """
    values = _numeric(world, START_NUMERIC)
    return (
        (values[0], values[1], values[2])
        if values is not None and len(values) == 3
        else (0.0, 0.0, 0.0)
    )


def uwb_anchors_xy_m(world: str | Path) -> np.ndarray | None:
    """The UWB anchors a world declares, ``(K, 2)`` m in its frame, or None (then ``uwb.anchors_*``
    apply).

    An MJCF world declares them as ``<custom><numeric name="uwb_anchors_xy_m" data="x0 y0 x1 y1
    ..."/>`` (the anchors are part of the site, like its walls; their height is ``uwb.anchor_z_m``).
    Raises :class:`MapError` for an odd count or fewer than 3 anchors.
    """
    values = _numeric(world, ANCHORS_NUMERIC)
    if values is None:
        return None
    if (
        len(values) % 2
        or not 3 <= len(values) // 2 <= 16
        or not all(math.isfinite(v) for v in values)
    ):
        raise MapError(
            f"{world_path(world)}: numeric {ANCHORS_NUMERIC} must hold 3 to 16 finite x y pairs, "
            f"got {len(values)} values"
        )
    return np.asarray(values, dtype=float).reshape(-1, 2)


@dataclass(frozen=True)
class ChargingStation:
    """Where a robot stands to charge: ``name``, ``x_m, y_m`` and heading ``yaw_rad`` in the world
    frame."""

    name: str
    x_m: float
    y_m: float
    yaw_rad: float


def charging_stations(world: str | Path) -> tuple[ChargingStation, ...]:
    """The charging stations ``world`` declares (``<custom><numeric name="charging_station:NAME"
    data="x_m y_m yaw_rad"/>``), by name; none for a map. Raises :class:`MapError` for one whose
    data is not three finite numbers."""
    out = []
    for name, values in sorted(_numerics(world).items()):
        if not name.startswith(CHARGER_PREFIX):
            continue
        if values is None or len(values) != 3 or not all(math.isfinite(v) for v in values):
            raise MapError(
                f"{world_path(world)}: numeric {name} must hold x_m y_m yaw_rad, three finite "
                f"numbers, got {values}"
            )
        out.append(ChargingStation(name[len(CHARGER_PREFIX) :], *values))
    return tuple(out)


@dataclass(frozen=True)
class Obstacle:
    """A box standing on the floor that the world file does not hold (an unmapped pallet jack, a
    box).

    Added to the world when the twin is built (``TwinOptions.obstacles``): the LiDAR sees it if it
    reaches the scan plane, the robot can hit it, and no map of the world holds it. ``x_m, y_m``:
    its centre in the world frame; ``size_m``: length, width, height; ``yaw_rad`` about +z.
    """

    name: str
    x_m: float
    y_m: float
    size_m: tuple[float, float, float]
    yaw_rad: float = 0.0

    def __post_init__(self) -> None:
        values = (self.x_m, self.y_m, self.yaw_rad, *self.size_m)
        if (
            len(self.size_m) != 3
            or not all(math.isfinite(v) for v in values)
            or min(self.size_m) <= 0
        ):
            raise ValueError(
                f"obstacle {self.name!r}: position and yaw finite, size_m three lengths > 0 "
                f"(got {self.x_m}, {self.y_m}, {self.size_m}, {self.yaw_rad})"
            )


class MapError(ValueError):
    """A map file (YAML or PGM) is invalid; the message is one line naming the file."""
