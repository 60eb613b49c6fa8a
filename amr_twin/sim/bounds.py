"""How long one simulated run may be: the bounds every command that simulates checks before the
work.

A run keeps its 100 Hz series in memory (about 0.1 MB and 0.02 s of CPU per simulated second), so
no run is longer than :data:`MAX_RUN_S`; longer studies are missions run in pieces. A run shorter
than :data:`MIN_RUN_S` holds too few samples to measure a step (the experiments' measures need at
least two). A recorded run also keeps every message until it writes them: :func:`memory_mb`
estimates a run's peak memory, which the commands compare with what the machine has available
(:func:`available_mb`) before they start. This module imports nothing: the command line reads it at
start-up.
"""

MAX_RUN_S = 3600.0
"""Longest run, simulated s."""
MIN_RUN_S = 0.1
"""Shortest run, simulated s: ten samples of the 100 Hz series."""


BASE_MB = 250.0
"""A run's process before it runs: the interpreter, numpy, MuJoCo, the model (measured: 219 to 286
MB at 60 simulated s with recordings, 85 MB without)."""
MB_PER_SIM_S = {"plain": 0.11, "recorded": 0.36, "recorded with sensors": 1.3}
"""Peak memory a run adds per simulated second, MB, measured by ``/usr/bin/time`` (maximum resident
size) at 60, 300 and 1200 simulated s: the series alone (also with ``--sensors``: their messages are
not kept); recorded (``--record``/``--mcap``: every message and pose kept until written); recorded
with ``--sensors`` (the LiDAR's scans and the IMU's samples kept as well)."""


RERUN_ADDRESS_SPACE_MB = 3000.0
"""Address space a run writing a Rerun recording (.rrd) reserves beyond its resident memory, MB: its
recorder's threads (measured VmPeak 3.2 GB against 0.2 GB resident for a 20 s run; 0.2 GB without
it, also with --mcap). Under ``ulimit -v`` below that, Rerun aborted the process (SIGABRT, a Rust
backtrace)."""


def duration_problem(duration_s: float) -> str | None:
    """Why ``duration_s`` is no run's length (None: it is one): ``"must be in [0.1, 3600] s
    ..."``."""
    if not MIN_RUN_S <= duration_s <= MAX_RUN_S:  # NaN fails too
        return (
            f"must be in [{MIN_RUN_S:g}, {MAX_RUN_S:g}] s (a run keeps its 100 Hz series in "
            f"memory, ~0.1 MB "
            "per simulated second: run a longer study as several runs)"
        )
    return None


def memory_mb(duration_s: float, recorded: bool = False, sensors: bool = False) -> float:
    """A run's estimated peak memory, MB (:data:`MB_PER_SIM_S`)."""
    kind = "plain" if not recorded else "recorded with sensors" if sensors else "recorded"
    return BASE_MB + MB_PER_SIM_S[kind] * duration_s


def address_space_mb() -> float | None:
    """The process' address-space limit (``ulimit -v``, RLIMIT_AS), MB; None when unlimited."""
    import resource

    soft = resource.getrlimit(resource.RLIMIT_AS)[0]
    return None if soft == resource.RLIM_INFINITY else soft / 1024 / 1024


def available_mb() -> float | None:
    """Memory the machine has available now, MB (``MemAvailable`` of /proc/meminfo); None where
    unknown."""
    try:
        with open("/proc/meminfo") as fh:
            for line in fh:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) / 1024
    except (OSError, ValueError, IndexError):
        return None
    return None
