"""Kept for code written against the flat layout: the Rerun recording moved to :mod:`amr_twin.recording.rerun_log`."""

from amr_twin.recording.rerun_log import *  # noqa: F401,F403
