"""One round of the sweep figure, in a process of its own: ``python -m amr_twin.bench.sweep_round
ROUND.pkl``.

A user's sweep starts in a fresh process: the model memos of :mod:`amr_twin.model.urdf` and
:mod:`amr_twin.model.mass` are empty (the disk caches are not), so a round timed in the bench's
own process after another would find them filled and run faster than any user's. Each round
therefore runs here: the imports untimed, then the 100-point sweep (8 s each, ``--jobs 1``,
into an empty folder: nothing reused) and, right after it, bare ``mj_step`` of the same
simulated time on a point's model from a running start, both in CPU time of this process.
``ROUND.pkl`` holds ``(cfg, spec)``: the parameters and the sweep (:data:`SWEEP`, or a smaller one
in the tests). One JSON object on stdout: ``sweep_cpu_s``, ``bare_point_s``, ``points``,
``simulated`` and the process id ``pid``.
"""

from __future__ import annotations

import json
import os
import pickle
import sys
import tempfile
from pathlib import Path

SWEEP_MASSES = [5.0 * i for i in range(10)]  # 0..45 kg
SWEEP_POSITIONS = ["center", "front", "rear", "left", "right"]
SWEEP_COMMANDS = ["linear:0.7", "angular:60:-1"]  # 10 x 5 x 2 = 100 runs
SWEEP_DURATION_S = 8.0
SWEEP = {
    "masses": SWEEP_MASSES,
    "positions": SWEEP_POSITIONS,
    "commands": SWEEP_COMMANDS,
    "duration_s": SWEEP_DURATION_S,
}
"""The benchmark's sweep: 100 points of 8 s."""


def sweep_round(cfg, spec: dict = SWEEP) -> dict:
    """Time the sweep ``spec`` of ``cfg`` and then bare physics of one point of it, CPU s (module
    notes)."""
    from amr_twin.bench.physics import bare_steps_s, timer
    from amr_twin.experiments.payload import point as payload_point, sweep as payload_sweep
    from amr_twin.assembly.twin import Twin, TwinOptions

    with tempfile.TemporaryDirectory(prefix="amr-twin-bench-") as tmp:
        t0 = timer()
        sweep = payload_sweep.run(
            cfg,
            Path(tmp),
            spec["masses"],
            spec["positions"],
            spec["commands"],
            duration_s=spec["duration_s"],
            jobs=1,
            progress=False,
        )
        cpu = timer() - t0
    twin = Twin(
        payload_point.with_payload(cfg, 20.0, (0.0, 0.0)), TwinOptions(world="empty", visuals=False)
    )
    twin.client.linear(0.7)
    twin.advance(1.0)  # the model a sweep point runs, moving
    bare = bare_steps_s(twin.physics, spec["duration_s"])
    return {
        "sweep_cpu_s": cpu,
        "bare_point_s": bare,
        "points": len(sweep["rows"]),
        "simulated": sweep["simulated"],
        "pid": os.getpid(),
    }


def main(argv: list[str]) -> int:
    cfg, spec = pickle.loads(Path(argv[0]).read_bytes())
    print(json.dumps(sweep_round(cfg, spec)))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
