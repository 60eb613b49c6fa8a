"""Kept for code written against the flat layout: the parameter file and its schema moved to :mod:`amr_twin.model.config`."""

from amr_twin.model.config import *  # noqa: F401,F403
