"""The experiments' registry: each package registers its spec, run entry point and result.

A Python user builds a spec, calls its ``validate()`` (ValueError, one line naming the field) and
runs it without the CLI; the CLI is an adapter over the same spec. A third party registers its own
experiment from its module (:meth:`amr_twin.base.registry.Registry.register`).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

from amr_twin.base.registry import Registry

__all__ = ["EXPERIMENTS", "Experiment"]


@dataclass(frozen=True)
class Experiment:
    """One registered experiment.

    Args:
        name: the experiment's name (``payload``), as the CLI names it.
        spec: the spec dataclass; its ``validate(...)`` raises ValueError naming the field.
        run: the entry point, ``run(spec, cfg, out_dir, **runner options)``.
        result: the typed result (or the type of its records).
        about: one line saying what it measures.
    """

    name: str
    spec: type
    run: Callable
    result: type
    about: str


EXPERIMENTS: Registry[Experiment] = Registry("experiment")
"""The experiments by name, in registration order (filled: :func:`.catalogue.experiments`)."""
