"""Kept for code written against the flat layout: the simulation loop moved to :mod:`amr_twin.sim.loop`."""

from amr_twin.sim.loop import *  # noqa: F401,F403
