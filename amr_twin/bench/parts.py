"""Where the loop's CPU time goes: ``python -m amr_twin.bench.parts [SIM_S] [ROUNDS]``.

Wraps the loop's parts (the C chunks, the odometry node, the IMU's and LiDAR's Python, the bus,
the hall edges and their delivery, the clock's events, ...) with ``time.process_time``, each
part's time exclusive of the wrapped parts it calls, then runs the bench scenario
(:mod:`amr_twin.bench.twin`) without and with sensors, each run followed by the floor
(:mod:`amr_twin.bench.physics`). Prints per part the median over the rounds of its CPU ms per
simulated second and its share of the floor. The wrappers replace methods of the classes for
the rest of the process: run it in a process of its own. docs/reference/speed.md shows a table it
made."""

from __future__ import annotations

import os
import statistics
import sys
import time
from collections import defaultdict

timer = time.process_time


class PartTimer:
    """Exclusive CPU s and calls per part name of the functions it :meth:`wrap`-ped."""

    def __init__(self):
        self.cpu_s: dict[str, float] = defaultdict(float)
        self.calls: dict[str, int] = defaultdict(int)
        self._stack: list[float] = []

    def wrap(self, name: str, fn):
        """``fn`` timed as ``name``: its CPU s without that of the wrapped functions it calls."""

        def timed(*args, **kwargs):
            self._stack.append(0.0)
            t0 = timer()
            try:
                return fn(*args, **kwargs)
            finally:
                spent = timer() - t0
                inner = self._stack.pop()
                self.cpu_s[name] += spent - inner
                self.calls[name] += 1
                if self._stack:
                    self._stack[-1] += spent

        return timed

    def patch(self, cls, method: str, name: str | None = None) -> None:
        """Replace ``cls.method`` by its timed wrapper (named ``name`` or ``Class.method``)."""
        setattr(cls, method, self.wrap(name or f"{cls.__name__}.{method}", getattr(cls, method)))

    def clear(self) -> None:
        self.cpu_s.clear()
        self.calls.clear()


def instrument(parts: PartTimer) -> None:
    """Wrap the loop's parts (before any twin is built: clock events hold bound methods)."""
    from amr_twin.controllers.arduino import ArduinoRuntime
    from amr_twin.controllers.odometry import WheelOdometry
    from amr_twin.estimation.published_pose import PublishedPose
    from amr_twin.recording.recorder import Recorder
    from amr_twin.ros.bus import Bus
    from amr_twin.sensors.hall import HallSensors
    from amr_twin.sensors.imu import ImuSensor
    from amr_twin.sensors.lidar import Lidar
    from amr_twin.sim import grid_loop, grid_rows, grid_steps
    from amr_twin.sim.actuation import Actuation
    from amr_twin.base.clock import VirtualClock
    from amr_twin.assembly.robot import Robot
    from amr_twin.assembly.world import World
    from amr_twin.sim.physics import Physics

    parts.patch(grid_steps.GridStepper, "run", "C chunks: mj_step and the C grid samplers")
    parts.patch(grid_loop.GridLoop, "run", "GridLoop.run: Python, mj_step after the last instant")
    parts.patch(VirtualClock, "run_until", "clock events (firmware, rosserial, wheel topics)")
    for cls, method in (
        (HallSensors, "edges_from_samples"),
        (Robot, "deliver_edges"),
        (World, "_step_physics"),
        (WheelOdometry, "publish"),
        (PublishedPose, "advance"),
        (PublishedPose, "retarget"),
        (ArduinoRuntime, "external_edge"),
        (Actuation, "apply"),
        (Physics, "check"),
        (Bus, "publish"),
        (ImuSensor, "_publish_next"),
        (ImuSensor, "_messages"),
        (Lidar, "_after_pose"),
        (Lidar, "_publish_next"),
        (Lidar, "cast"),
        (Lidar, "_finish"),
        (grid_rows.GridRows, "grid_resume"),
    ):
        parts.patch(cls, method)
    for method in [m for m in dir(Recorder) if m.startswith("_on")]:
        parts.patch(Recorder, method)


def profile_parts(cfg, sim_s: float = 16.0, rounds: int = 5) -> dict:
    """``{"loop" | "sensors": [{"total", "floor", "parts", "calls"} per round]}``: CPU s per
    simulated s of
    the run, of its floor and of each part (``"(rest)"``: what no wrapper took)."""
    from amr_twin.bench.physics import floor_s
    from amr_twin.bench.twin import twin_run

    parts = PartTimer()
    instrument(parts)
    for sensors in (False, True):  # warm-up
        twin_run(cfg, min(sim_s, 1.0), sensors=sensors)
    out: dict[str, list] = {"loop": [], "sensors": []}
    for _ in range(rounds):
        for name in out:
            parts.clear()
            run = twin_run(cfg, sim_s, sensors=name == "sensors", snapshot=True)
            floor = floor_s(run.path) / sim_s
            each = {k: v / sim_s for k, v in parts.cpu_s.items()}
            each["(rest)"] = run.cpu_s / sim_s - sum(each.values())
            out[name].append(
                {
                    "total": run.cpu_s / sim_s,
                    "floor": floor,
                    "parts": each,
                    "calls": dict(parts.calls),
                }
            )
    return out


def report(result: dict) -> list[str]:
    """Lines per run kind: its total and floor, then each part's median ms per simulated s and
    share of the floor."""
    lines = []
    for name, rows in result.items():
        floor = statistics.median(r["floor"] for r in rows)
        lines.append(
            f"{name}: {1e3 * statistics.median(r['total'] for r in rows):.2f} ms per simulated s, "
            "floor "
            f"{1e3 * floor:.2f}, "
            f"ratio {statistics.median(r['total'] / r['floor'] for r in rows):.3f}"
        )
        names = {k for r in rows for k in r["parts"]}
        med = {k: statistics.median(r["parts"].get(k, 0.0) for r in rows) for k in names}
        for k in sorted(names, key=lambda k: -med[k]):
            lines.append(
                f"  {k:48s} {1e3 * med[k]:7.3f} ms {100 * med[k] / floor:6.1f} % of floor, "
                f"{rows[0]['calls'].get(k, '-')} calls"
            )
    return lines


def main(argv: list[str]) -> int:
    from amr_twin.model.config import load_config

    sim_s, rounds = (float(argv[0]) if argv else 16.0), (int(argv[1]) if len(argv) > 1 else 5)
    result = profile_parts(load_config(), sim_s, rounds)
    print(f"load average {os.getloadavg()}")
    print("\n".join(report(result)))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
