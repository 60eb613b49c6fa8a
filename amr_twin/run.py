"""Kept for code written against the flat layout: the run commands and missions moved to :mod:`amr_twin.sim.run`."""

from amr_twin.sim.run import *  # noqa: F401,F403
