"""Wall-time figures of the experiment suites: ``amr-twin bench --suites`` (issue #6 speed targets).

Unlike the per-step ratios of :mod:`amr_twin.benchmark` (CPU time against bare
physics), these targets are wall times on the 2-core machine: the chapter 5 suite
(132 simulated s) in under 10 s, a 100-run payload sweep in under 2 minutes. So
they are measured with ``time.perf_counter`` and printed with the load average, by
which a reader can judge how busy the machine was. Results go to a temporary
folder that is removed afterwards.
"""

from __future__ import annotations

import os
import tempfile
import time
from pathlib import Path

from .config import TwinConfig

SWEEP_MASSES = [5.0 * i for i in range(10)]                # 0..45 kg
SWEEP_POSITIONS = ["center", "front", "rear", "left", "right"]
SWEEP_COMMANDS = ["linear:0.7", "angular:60:-1"]           # 10 x 5 x 2 = 100 runs
SWEEP_DURATION_S = 8.0


def suite_figures(cfg: TwinConfig, jobs: int = 2) -> dict:
    """Run the chapter 5 suite, a 100-run sweep and the fusion experiment; return their wall times, s."""
    from .experiments import chapter5, fusion, payload_sweep

    load_before = os.getloadavg()[0]
    t0 = time.perf_counter()
    ch5 = chapter5.run(cfg, jobs=jobs, progress=False)
    ch5_wall = time.perf_counter() - t0
    with tempfile.TemporaryDirectory(prefix="amr-twin-bench-") as tmp:
        t0 = time.perf_counter()
        sweep = payload_sweep.run(cfg, Path(tmp), SWEEP_MASSES, SWEEP_POSITIONS, SWEEP_COMMANDS,
                                  duration_s=SWEEP_DURATION_S, jobs=jobs, progress=False)
        sweep_wall = time.perf_counter() - t0
    t0 = time.perf_counter()
    fus = fusion.run(cfg, progress=False)
    fusion_wall = time.perf_counter() - t0
    return {
        "jobs": jobs,
        "chapter5_sim_s": round(float(ch5["sim_s"]), 1),
        "chapter5_wall_s": round(ch5_wall, 2),
        "sweep_runs": len(sweep["rows"]),
        "sweep_simulated": sweep["simulated"],
        "sweep_sim_s": round(len(sweep["rows"]) * SWEEP_DURATION_S, 1),
        "sweep_wall_s": round(sweep_wall, 2),
        "fusion_sim_s": round(fus.sim_s, 1),
        "fusion_wall_s": round(fusion_wall, 2),
        "load_average_1min_before": round(load_before, 2),
        "load_average_1min_after": round(os.getloadavg()[0], 2),
        "suites_timer": "perf_counter (wall)",
    }
