"""Cost of recording: a run with the capture attached and its ``.rrd`` written.

:func:`recording_run` is the ``recording`` figure of ``amr-twin bench``: the benchmark's loop
(:mod:`amr_twin.bench.twin`) with the capture attached, its CPU time with the writing of the
``.rrd`` after it. :func:`recording_figures` (``python -m amr_twin.bench.recording``) times a
chapter 5 run (16 s, linear 0.7 m/s) with and without ``--record`` (and ``.mcap``), wall time,
best of ``repeats``; imports (rerun takes ~1 s) are done before timing.
"""

from __future__ import annotations

import tempfile
import time
from pathlib import Path

from amr_twin.bench.physics import timed_advance, timer
from amr_twin.bench.twin import BENCH_START, Timed
from amr_twin.model.config import TwinConfig
from amr_twin.assembly.twin import Twin, TwinOptions
from amr_twin.assembly.command import Command
from amr_twin.recording.run import run_mission

DURATION_S = 16.0
STEPS = [(0.0, Command("linear", speed_m_s=0.7))]


def recording_run(cfg: TwinConfig, sim_s: float) -> Timed:
    """The benchmark's loop with the capture attached (before the timing), timed with the ``.rrd``
    written to a temporary folder after it; ``info["rrd_bytes"]``: the file's size."""
    import rerun  # noqa: F401 - imported outside the timing

    from amr_twin.recording.rerun_capture import attach
    from amr_twin.recording.rerun_log import record_run

    twin = Twin(cfg, TwinOptions(start_xy_yaw=BENCH_START))
    twin.client.linear(0.7)
    attach(twin)
    cpu, _path = timed_advance(twin, sim_s)
    with tempfile.TemporaryDirectory(prefix="amr-twin-bench-") as tmp:
        rrd = Path(tmp) / "run.rrd"
        t0 = timer()
        record_run(twin, rrd_path=rrd)
        cpu += timer() - t0
        size = rrd.stat().st_size
    return Timed(cpu, sim_s, twin, None, {"rrd_bytes": size})


def _timed(cfg: TwinConfig, rrd: Path | None = None, mcap: Path | None = None) -> float:
    from amr_twin.recording.rerun_capture import attach
    from amr_twin.recording.rerun_log import record_run

    options = TwinOptions()
    t0 = time.perf_counter()
    twin = Twin(cfg, options)
    if rrd is None and mcap is None:
        run_mission(cfg, STEPS, DURATION_S, options, twin=twin)
    else:
        attach(twin)
        result = run_mission(cfg, STEPS, DURATION_S, options, twin=twin)
        record_run(twin, rrd_path=rrd, mcap_path=mcap, result=result)
    return time.perf_counter() - t0


def recording_figures(cfg: TwinConfig, repeats: int = 3) -> dict:
    """{"run_s", "run_record_s", "record_ratio", "run_record_mcap_s", "record_mcap_ratio",
    sizes}."""
    import mcap.writer  # noqa: F401 - imports outside the timing
    import rerun  # noqa: F401

    with tempfile.TemporaryDirectory() as tmp:
        rrd, mcap = Path(tmp) / "run.rrd", Path(tmp) / "run.mcap"
        run_s = min(_timed(cfg) for _ in range(repeats))
        rec_s = min(_timed(cfg, rrd) for _ in range(repeats))
        both_s = min(_timed(cfg, rrd, mcap) for _ in range(repeats))
        sizes = {"rrd_bytes": rrd.stat().st_size, "mcap_bytes": mcap.stat().st_size}
    return {
        "run_s": run_s,
        "run_record_s": rec_s,
        "record_ratio": rec_s / run_s,
        "run_record_mcap_s": both_s,
        "record_mcap_ratio": both_s / run_s,
        **sizes,
    }


if __name__ == "__main__":  # python -m amr_twin.bench.recording
    import json

    from amr_twin.model.config import load_config

    print(json.dumps(recording_figures(load_config()), indent=1))
