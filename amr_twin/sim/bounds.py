"""How long one simulated run may be: the bounds every command that simulates checks before the work.

A run keeps its 100 Hz series in memory (about 70 MB and a minute of CPU per simulated hour), so
no run is longer than :data:`MAX_RUN_S`; longer studies are missions run in pieces. A run shorter
than :data:`MIN_RUN_S` holds too few samples to measure a step (the experiments' measures need at
least two). This module imports nothing: the command line reads it at start-up.
"""

MAX_RUN_S = 3600.0
"""Longest run, simulated s."""
MIN_RUN_S = 0.1
"""Shortest run, simulated s: ten samples of the 100 Hz series."""


def duration_problem(duration_s: float) -> str | None:
    """Why ``duration_s`` is no run's length (None: it is one): ``"must be in [0.1, 3600] s ..."``."""
    if not MIN_RUN_S <= duration_s <= MAX_RUN_S:  # NaN fails too
        return (f"must be in [{MIN_RUN_S:g}, {MAX_RUN_S:g}] s (a run keeps its 100 Hz series in memory, ~70 MB "
                "per simulated hour: run a longer study as several runs)")
    return None
