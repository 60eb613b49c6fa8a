"""Configurations drawn from a :class:`~amr_twin.calibration.uncertainty.ParameterSpace`: the drawn
values, each sample's overrides and its configuration (:class:`Draws`)."""

from __future__ import annotations

import hashlib
import json
from dataclasses import dataclass

import numpy as np

from amr_twin.model.config import TwinConfig
from amr_twin.model.parameter_spreads import with_values


@dataclass(frozen=True)
class Draws:
    """Configurations drawn from a :class:`ParameterSpace`.

    ``names``: the drawn dimensions (``key`` or ``key[i]`` for a vector element), ``values``
    (n, d) their values; ``overrides[i]``: every parameter sample ``i`` changes (followers
    and shifted calibrated parameters included), ``{dotted key: value}``; ``clipped``: per
    name, how many draws were clipped to the bounds.
    """

    names: tuple[str, ...]
    values: np.ndarray
    overrides: tuple[dict, ...]
    seed: int
    sampler: str
    clipped: dict[str, int]

    def __len__(self) -> int:
        return len(self.overrides)

    def config(self, base: TwinConfig, i: int) -> TwinConfig:
        """``base`` with sample ``i``'s values (validated; one-line :class:`ConfigError`)."""
        return with_values(base, self.overrides[i])

    def sample_id(self, i: int) -> str:
        """10 hex digits naming sample ``i``'s values (part of a sweep's run keys)."""
        return hashlib.sha256(json.dumps(self.overrides[i], sort_keys=True).encode()).hexdigest()[
            :10
        ]

    def table(self) -> list[dict]:
        """One row per sample: ``sample``, ``id`` and each drawn dimension's value."""
        return [
            {"sample": i, "id": self.sample_id(i), **dict(zip(self.names, row.tolist()))}
            for i, row in enumerate(self.values)
        ]
