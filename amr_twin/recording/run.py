"""Python API: run one wheel command (or a timed list of them) on a twin and get its time series.

>>> from amr_twin.model.config import load_config
>>> from amr_twin.recording.run import run_command
>>> from amr_twin.assembly.command import Command
>>> result = run_command(load_config(), Command("motor", wheel="left", speed_m_s=1.0), 18.0)
>>> result.series.published[0]  # (k, 2): t_s, rpm as published on wheel0_Vel
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

from amr_twin.model.config import TwinConfig
from amr_twin.recording.fault_effects import fault_effects
from amr_twin.recording.recorder import RunSeries, attach_recorder
from amr_twin.sim.bounds import MAX_RUN_S
from amr_twin.assembly.command import Command
from amr_twin.assembly.twin import Twin, TwinOptions

UNTIL_STOPPED_US = 1 << 62
"""The end of a run of ``duration_s = inf``, us (~146 000 years)."""


@dataclass
class RunResult:
    """What :func:`run_command` returns."""

    commands: list[tuple[float, Command]]
    codes: list[int]
    wheel_command: list[float] | None  # the last [motionL, speedL, motionR, speedR] sent
    series: RunSeries
    sim_s: float
    wall_s: float
    errors: list[str] = field(default_factory=list)
    collisions: list[dict] = field(
        default_factory=list
    )  # amr_twin.sim.collisions.Collision.as_dict()
    halted: bool = False  # stopped at the first collision (TwinOptions.stop_on_collision)
    faults: list[dict] = field(default_factory=list)  # injected faults and their effect
    tyre_timestep: dict | None = (
        None  # the tyres' guard halved the timestep: TyreTimestep.as_dict(); else None
    )


def run_mission(
    cfg: TwinConfig,
    steps: list[tuple[float, Command]],
    duration_s: float,
    options: TwinOptions = TwinOptions(),
    twin: Twin | None = None,
) -> RunResult:
    """Send each command at its time (s from the start) and run for ``duration_s`` (``math.inf``:
    until ``twin.stop()``, called from a hook, another thread's call or a signal handler; a stopped
    run's ``sim_s`` is where it stopped)."""
    if not (
        0 < duration_s <= MAX_RUN_S or duration_s == math.inf
    ):  # the commands check theirs first
        raise ValueError(f"duration_s: {duration_s} must be in (0, {MAX_RUN_S:g}] s or inf")
    steps = sorted(steps, key=lambda s: s[0])
    if any(t < 0 or t > duration_s for t, _ in steps):
        raise ValueError(f"mission: command times must lie in [0, {duration_s}] s")
    wall0 = time.perf_counter()
    twin = twin or Twin(cfg, options)
    recorder = attach_recorder(twin)
    codes, errors, last = [], [], None
    for t_s, command in steps:
        twin.advance_to_us(int(round(t_s * 1e6)))
        if (
            twin.halted or twin.stopped
        ):  # stopped by a collision or from outside: the later commands are not sent
            break
        code = command.send(twin)
        codes.append(code)
        if code != 0:
            errors.append(twin.client.last_error or f"code {code}")
        elif twin.client.last_request is not None:
            r = twin.client.last_request
            last = [r.motionL, r.speedL, r.motionR, r.speedR]
    twin.advance_to_us(int(round(duration_s * 1e6)) if duration_s != math.inf else UNTIL_STOPPED_US)
    series = recorder.series()
    return RunResult(
        commands=steps[: len(codes)],
        codes=codes,
        wheel_command=last,
        series=series,
        sim_s=twin.t_s if twin.halted or twin.stopped else duration_s,
        wall_s=time.perf_counter() - wall0,
        errors=errors,
        collisions=[c.as_dict() for c in twin.observables.collisions],
        halted=twin.halted,
        faults=fault_effects(twin.faults, series) if twin.faults is not None else [],
        tyre_timestep=twin.tyre_timestep.as_dict() if twin.tyre_timestep.halvings else None,
    )


def run_command(
    cfg: TwinConfig, command: Command, duration_s: float, options: TwinOptions = TwinOptions()
) -> RunResult:
    """Send one command at t = 0 and run for ``duration_s`` simulated seconds."""
    return run_mission(cfg, [(0.0, command)], duration_s, options)


def warm_up() -> None:
    """A pool worker's start-up (:func:`amr_twin.base.process_pool.worker_pool`): nothing to run,
    as unpickling it imports this module, and with it the model build and the loop, before the
    first item."""
