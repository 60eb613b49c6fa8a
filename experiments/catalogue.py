"""The built-in experiments, registered: importing each package's spec module fills the registry."""

from __future__ import annotations

from amr_twin.base.registry import Registry
from amr_twin.experiments.registry import EXPERIMENTS, Experiment


def experiments() -> Registry[Experiment]:
    """The registry with the built-in experiments in it (and any a third party registered)."""
    # each spec module registers its experiment when imported
    from amr_twin.experiments.chapter5 import spec as chapter5  # noqa: F401
    from amr_twin.experiments.fleet import spec as fleet  # noqa: F401
    from amr_twin.experiments.fusion import spec as fusion  # noqa: F401
    from amr_twin.experiments.navigation import spec as navigation  # noqa: F401
    from amr_twin.experiments.payload import spec as payload  # noqa: F401
    from amr_twin.experiments.umbmark import spec as umbmark  # noqa: F401

    return EXPERIMENTS
