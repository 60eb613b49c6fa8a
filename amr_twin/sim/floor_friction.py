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
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from amr_twin.model.config import TwinConfig
from amr_twin.model.tyre_numeric import FIELD_CELLS

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
