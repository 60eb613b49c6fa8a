"""The floor's friction from patch to patch: a seeded field the brush tyres look up at each contact.

A warehouse floor is not one coefficient: dust, a wet or a polished patch lower the friction of
rubber on concrete below the clean floor's (``wheel.friction``). With ``sim.floor_friction_field``
on, each run draws a field from its seed (stream :data:`STREAM`): friction coefficients at the nodes
of a square grid ``sim.floor_patch_m`` apart, each uniform between ``sim.floor_friction_low`` and
``wheel.friction``, the grid :data:`~amr_twin.model.tyre_numeric.FIELD_CELLS` nodes a side and
repeating beyond (world frame, origin at a node). The tyres (:mod:`amr_twin.sim.tyres` and its C
twin) interpolate it bilinearly at each contact point, every physics step; the same seed gives
the same field, and the two engines the same bits. It acts through the brush's saturation (the
patch slides at ``3 mu N`` of deflection force) and the spin torque's cap: with the rigid contact
(``wheel.tyre_slip`` off) there is nothing for it to act on and it is not drawn.

Part of the physics layer: :func:`set_friction_field` writes the field into the tyres' user data
(``Physics.set_floor_friction``); :func:`friction_at` is the look-up's Python twin.

Part of the physics layer (``PHYSICS_LAYER``): writes the floor's friction field into the tyres'
user data of MjModel/MjData.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from amr_twin.model.config import TwinConfig
from amr_twin.model.tyre_numeric import FIELD_CELLS, FIELD_OFFSET, numeric_ids

PHYSICS_LAYER = True

STREAM = 5
"""Index of the floor's stream of a run's seed (1 IMU, 2 LiDAR, 3 UWB, 4 the robot's own errors)."""


@dataclass(frozen=True)
class FrictionField:
    """Friction coefficients ``values`` (FIELD_CELLS, FIELD_CELLS), row y, column x, at nodes
    ``spacing_m`` apart from the world origin, repeating."""

    spacing_m: float
    values: np.ndarray


def draw(cfg: TwinConfig, seed: int) -> FrictionField:
    """The field of the run ``seed`` (the same seed, the same bytes)."""
    rng = np.random.default_rng([int(seed), STREAM])
    low, high = cfg.sim.floor_friction_low, cfg.wheel.friction
    values = low + (high - low) * rng.random((FIELD_CELLS, FIELD_CELLS))
    return FrictionField(float(cfg.sim.floor_patch_m), values)


def _userdata_starts(model) -> list[int]:
    """Where each robot's tyre user data starts in ``model``'s MjData (none: no brush tyres)."""
    return [int(model.numeric_data[int(model.numeric_adr[n]) + 1]) for n in numeric_ids(model)]


def set_friction_field(model, data, spacing_m: float, values) -> None:
    """Put the floor's friction field in ``data``: ``values`` (FIELD_CELLS, FIELD_CELLS) friction
    coefficients at nodes ``spacing_m`` apart (row y, column x; repeating), or ``values=None`` for
    none (the model's ``wheel.friction`` everywhere); every robot's tyres get the field. ValueError
    for a model without tyres."""
    starts = _userdata_starts(model)
    if not starts:
        raise ValueError("friction field: the model has no brush tyres (wheel.tyre_slip is off)")
    flat = None if values is None else [float(v) for row in values for v in row]
    for start in starts:
        at = start + FIELD_OFFSET
        if flat is None:
            data.userdata[at : at + 2 + FIELD_CELLS**2] = 0.0
            continue
        data.userdata[at] = float(FIELD_CELLS)
        data.userdata[at + 1] = float(spacing_m)
        data.userdata[at + 2 : at + 2 + FIELD_CELLS**2] = flat


def friction_at(field, x: float, y: float) -> float:
    """The Python twin of ``friction_at`` (tyres.c; :func:`amr_twin.sim.tyres.tyre_forces` calls
    it): the coefficient at (x, y), m, of ``field`` (the tyres' user data from
    :data:`~amr_twin.model.tyre_numeric.FIELD_OFFSET` on, a list): bilinear between the nodes,
    repeating every n nodes; the same operations in the same order as the C."""
    n = int(field[0])
    cell = field[1]
    u, w = x / cell, y / cell
    iu, iw = math.floor(u), math.floor(w)
    fx, fy = u - iu, w - iw
    i0, j0 = iu % n, iw % n
    i1, j1 = (i0 + 1) % n, (j0 + 1) % n
    v = 2
    a = field[v + j0 * n + i0] + fx * (field[v + j0 * n + i1] - field[v + j0 * n + i0])
    b = field[v + j1 * n + i0] + fx * (field[v + j1 * n + i1] - field[v + j1 * n + i0])
    return a + fy * (b - a)
