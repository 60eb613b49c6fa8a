"""``--world generated:SEED[?door=W]``: a hall of :mod:`amr_twin.model.world_generator` as an MJCF
world file.

The name is parsed by :func:`parse` (``SEED`` a non-negative integer; ``door=W``: every doorway
``W`` m wide, in :data:`~amr_twin.model.world_generator.FORCED_DOOR_RANGE_M`). :func:`mjcf` writes
the hall as MJCF text (same seed, same bytes), with the default start and the UWB anchors as the
hand-made worlds declare them (``<custom><numeric>`` ``start_xy_yaw``, ``uwb_anchors_xy_m``) and
each doorway as ``door<k>_x_y_width_m``. :func:`world_file` writes it once into the disk cache
(``worlds/``; a temporary folder when the cache is off), where every consumer of a world's file
reads it (:func:`amr_twin.model.worlds.world_path`).
"""

from __future__ import annotations

import functools
import os
import tempfile
from pathlib import Path

from amr_twin.model.world_generator import FORCED_DOOR_RANGE_M, GeneratedWorld, generate

PREFIX = "generated:"
MAX_SEED = 2**31 - 1


class GeneratedWorldError(ValueError):
    """A ``generated:`` world name is invalid; the message is one line saying what is allowed."""


def is_generated(world) -> bool:
    """Whether ``world`` names a generated hall."""
    return isinstance(world, str) and world.startswith(PREFIX)


def parse(world: str) -> tuple[int, float | None]:
    """``(seed, door_width_m or None)`` of ``generated:SEED[?door=W]``; raises
    :class:`GeneratedWorldError`."""
    usage = (
        f"--world {world}: expected generated:SEED or generated:SEED?door=W (SEED an integer in "
        f"[0, {MAX_SEED}], "
        f"W in [{FORCED_DOOR_RANGE_M[0]:g}, {FORCED_DOOR_RANGE_M[1]:g}] m)"
    )
    body = world[len(PREFIX) :]
    seed_text, _, query = body.partition("?")
    if not seed_text.isdigit() or int(seed_text) > MAX_SEED:
        raise GeneratedWorldError(usage)
    door = None
    if query:
        key, _, value = query.partition("=")
        try:
            door = float(value)
        except ValueError:
            raise GeneratedWorldError(usage) from None
        if key != "door" or not FORCED_DOOR_RANGE_M[0] <= door <= FORCED_DOOR_RANGE_M[1]:
            raise GeneratedWorldError(usage)
    return int(seed_text), door


def name(seed: int, door_width_m: float | None = None) -> str:
    """The world name of a hall: ``generated:SEED`` or ``generated:SEED?door=W``."""
    return f"{PREFIX}{seed}" + ("" if door_width_m is None else f"?door={door_width_m:g}")


@functools.lru_cache(maxsize=32)
def hall(world: str) -> GeneratedWorld:
    """The drawn hall of a ``generated:`` world name."""
    seed, door = parse(world)
    return generate(seed, door)


def _f(*values: float) -> str:
    return " ".join(f"{v:.6g}" for v in values)


def mjcf(world: str) -> str:
    """The MJCF text of a ``generated:`` world (module docstring)."""
    h = hall(world)
    W, H = h.size_m
    doors = "\n".join(
        f'    <numeric name="{d.name}_x_y_width_m" data="{_f(d.x_m, d.y_m, d.width_m)}"/>'
        for d in h.doors
    )
    lines = [
        f"<!-- {world}: drawn by amr_twin.model.world_generator (docs/explanation/navigation.md). "
        f"{W:g} x {H:g} m, {len(h.doors)} doorway(s) "
        f"{', '.join(f'{d.width_m:g} m' for d in h.doors)}. -->",
        f'<mujoco model="{name(*parse(world)).replace(":", "_").replace("?", "_")}">',
        "  <custom>",
        f'    <numeric name="start_xy_yaw" data="{_f(*h.start_xy_yaw)}"/>',
        f'    <numeric name="uwb_anchors_xy_m" '
        f'data="{_f(*(v for a in h.anchors_xy_m for v in a))}"/>',
        doors,
        "  </custom>",
        '  <visual><headlight ambient="0.35 0.35 0.35" diffuse="0.5 0.5 0.5"/></visual>',
        "  <asset>",
        '    <material name="concrete" rgba="0.55 0.55 0.55 1" reflectance="0.05"/>',
        '    <material name="wall" rgba="0.85 0.84 0.80 1"/>',
        '    <material name="rack" rgba="0.15 0.30 0.65 1"/>',
        '    <material name="beam" rgba="0.95 0.50 0.10 1"/>',
        '    <material name="goods" rgba="0.80 0.72 0.55 1"/>',
        '    <material name="pillar" rgba="0.65 0.65 0.62 1"/>',
        '    <material name="cage" rgba="0.35 0.35 0.35 0.6"/>',
        "  </asset>",
        "  <worldbody>",
        '    <light name="sun" pos="0 0 8" dir="0 0 -1" directional="true"/>',
        f'    <geom name="floor" type="plane" size="{_f(W / 2 + 1, H / 2 + 1, 0.1)}" '
        f'material="concrete"/>',
    ]
    lines += [
        f'    <geom name="{b.name}" type="box" pos="{_f(*b.centre_m)}" size="{_f(*b.half_m)}" '
        f'material="{b.material}"/>'
        for b in h.boxes
    ]
    lines += ["  </worldbody>", "</mujoco>", ""]
    return "\n".join(lines)


def _folder() -> Path:
    from amr_twin.base.disk_cache import cache_dir

    folder = cache_dir("worlds")
    return (
        folder
        if folder is not None
        else Path(tempfile.gettempdir()) / f"amr-twin-worlds-{os.getuid()}"
    )


def world_file(world: str) -> Path:
    """The MJCF file of a ``generated:`` world, written (whole, by one rename) unless it holds these
    bytes."""
    from amr_twin.base.disk_cache import read_entry, store

    seed, door = parse(world)
    text = mjcf(world).encode()
    path = _folder() / (f"generated_{seed}" + ("" if door is None else f"_door{door:g}") + ".xml")
    if read_entry(path) != text:
        store(path, text)
        if read_entry(path) != text:
            raise OSError(f"--world {world}: cannot write its MJCF file {path}")
    return path
