"""Python API: run one wheel command (or a timed list of them) and get the time series.

>>> from amr_twin.model.config import load_config
>>> from amr_twin.sim.run import Command, run_command
>>> result = run_command(load_config(), Command("motor", wheel="left", direction="forward", speed_m_s=1.0), 18.0)
>>> result.series.published[0]  # (k, 2): t_s, rpm as published on wheel0_Vel
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

from amr_twin.model.config import TwinConfig
from amr_twin.sim.bounds import MAX_RUN_S
from amr_twin.sim.loop import Twin, TwinOptions
from amr_twin.recording.recorder import RunSeries

KINDS = ("linear", "angular", "motor", "stop")
UNTIL_STOPPED_US = 1 << 62
"""The end of a run of ``duration_s = inf``, us (~146 000 years)."""


@dataclass(frozen=True)
class Command:
    """One wheel_Command_Client call, as in the terminal menu of fig. 3.2.

    kind : "linear" (speed_m_s, negative = backward), "angular" (speed_deg_s,
        icc_m; REP-103: ICC positive to the left), "motor" (wheel, direction,
        speed_m_s) or "stop".
    """

    kind: str
    speed_m_s: float = 0.0
    speed_deg_s: float = 0.0
    icc_m: float = 0.0
    wheel: str = "left"
    direction: str = "forward"

    def __post_init__(self) -> None:
        if self.kind not in KINDS:
            raise ValueError(f"command kind: {self.kind!r} is not one of {', '.join(KINDS)}")
        for name in ("speed_m_s", "speed_deg_s", "icc_m"):
            value = getattr(self, name)
            if not math.isfinite(value):
                raise ValueError(f"{name}: {value} must be a finite number")
        if self.wheel not in ("left", "right"):
            raise ValueError(f"wheel: {self.wheel!r} must be left or right")
        if self.direction not in ("forward", "backward"):
            raise ValueError(f"direction: {self.direction!r} must be forward or backward")

    @classmethod
    def parse(cls, text: str, what: str = "command") -> "Command":
        """``linear:V``, ``angular:DEG_S:ICC_M``, ``motor:WHEEL:V`` (signed), ``motor:WHEEL:DIR:V`` or ``stop``.

        The form used by ``amr-twin sweep --commands`` and the ``command`` column of a
        calibration log (m/s, deg/s, m). ``what`` names the input in the error message.
        """
        parts = text.strip().split(":")
        try:
            if parts[0] == "linear" and len(parts) == 2:
                return cls("linear", speed_m_s=float(parts[1]))
            if parts[0] == "angular" and len(parts) == 3:
                return cls("angular", speed_deg_s=float(parts[1]), icc_m=float(parts[2]))
            if parts[0] == "motor" and len(parts) == 3:
                v = float(parts[2])
                return cls("motor", wheel=parts[1], direction="forward" if v >= 0 else "backward", speed_m_s=abs(v))
            if parts[0] == "motor" and len(parts) == 4:
                return cls("motor", wheel=parts[1], direction=parts[2], speed_m_s=float(parts[3]))
            if parts[0] == "stop" and len(parts) == 1:
                return cls("stop")
        except ValueError as exc:
            raise ValueError(f"{what} {text!r}: {exc}") from None
        raise ValueError(f"{what} {text!r}: expected linear:V, angular:DEG_S:ICC_M, motor:WHEEL:V, "
                         "motor:WHEEL:DIR:V or stop")

    def send(self, twin: Twin) -> int:
        """Call the client as the menu would; return its code (0 ok, 1 value error, -1 failed)."""
        client = twin.client
        if self.kind == "linear":
            return client.linear(self.speed_m_s)
        if self.kind == "angular":
            return client.angular(self.speed_deg_s, self.icc_m)
        if self.kind == "motor":
            return client.motor(self.wheel, self.direction, self.speed_m_s)
        return client.stop()

    def dry_run(self, cfg: TwinConfig):
        """Send the command to a client of its own, with no twin (its conversions and range checks only):
        the client after the call (``last_request``, ``last_error``)."""
        from amr_twin.controllers.wheel_command import WheelCommandClient, WheelCommandService
        from amr_twin.ros.bus import Bus
        from amr_twin.base.clock import VirtualClock

        bus = Bus(VirtualClock())
        WheelCommandService(bus)
        client = WheelCommandClient(bus, wheel_radius_m=cfg.wheel.radius_m, half_separation_m=cfg.wheel.separation_m / 2)
        self.send(type("Twinless", (), {"client": client})())
        return client

    def describe(self) -> dict:
        """The command as a JSON-ready dict."""
        out = {"kind": self.kind}
        if self.kind == "linear":
            out["speed_m_s"] = self.speed_m_s
        elif self.kind == "angular":
            out.update(speed_deg_s=self.speed_deg_s, icc_m=self.icc_m)
        elif self.kind == "motor":
            out.update(wheel=self.wheel, direction=self.direction, speed_m_s=self.speed_m_s)
        return out


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
    collisions: list[dict] = field(default_factory=list)  # amr_twin.sim.collisions.Collision.as_dict()
    halted: bool = False  # stopped at the first collision (TwinOptions.stop_on_collision)
    faults: list[dict] = field(default_factory=list)  # injected faults and their effect
    tyre_timestep: dict | None = None  # the tyres' guard halved the timestep: TyreTimestep.as_dict(); else None


def run_mission(cfg: TwinConfig, steps: list[tuple[float, Command]], duration_s: float,
                options: TwinOptions = TwinOptions(), twin: Twin | None = None) -> RunResult:
    """Send each command at its time (s from the start) and run for ``duration_s`` (``math.inf``: until
    ``twin.stop()``, called from a hook, another thread's call or a signal handler; a stopped run's ``sim_s``
    is where it stopped)."""
    if not (0 < duration_s <= MAX_RUN_S or duration_s == math.inf):  # the commands check theirs first
        raise ValueError(f"duration_s: {duration_s} must be in (0, {MAX_RUN_S:g}] s or inf")
    steps = sorted(steps, key=lambda s: s[0])
    if any(t < 0 or t > duration_s for t, _ in steps):
        raise ValueError(f"mission: command times must lie in [0, {duration_s}] s")
    wall0 = time.perf_counter()
    twin = twin or Twin(cfg, options)
    codes, errors, last = [], [], None
    for t_s, command in steps:
        twin.advance_to_us(int(round(t_s * 1e6)))
        if twin.halted or twin.stopped:  # stopped by a collision or from outside: the later commands are not sent
            break
        code = command.send(twin)
        codes.append(code)
        if code != 0:
            errors.append(twin.client.last_error or f"code {code}")
        elif twin.client.last_request is not None:
            r = twin.client.last_request
            last = [r.motionL, r.speedL, r.motionR, r.speedR]
    twin.advance_to_us(int(round(duration_s * 1e6)) if duration_s != math.inf else UNTIL_STOPPED_US)
    series = twin.recorder.series()
    return RunResult(commands=steps[:len(codes)], codes=codes, wheel_command=last, series=series,
                     sim_s=twin.t_s if twin.halted or twin.stopped else duration_s, wall_s=time.perf_counter() - wall0,
                     errors=errors, collisions=twin.collisions.as_dicts(), halted=twin.halted,
                     faults=twin.faults.report(series) if twin.faults is not None else [],
                     tyre_timestep=twin.tyre_timestep.as_dict() if twin.tyre_timestep.halvings else None)


def run_command(cfg: TwinConfig, command: Command, duration_s: float,
                options: TwinOptions = TwinOptions()) -> RunResult:
    """Send one command at t = 0 and run for ``duration_s`` simulated seconds."""
    return run_mission(cfg, [(0.0, command)], duration_s, options)


def warm_up() -> None:
    """A pool worker's start-up (:func:`amr_twin.base.process_pool.worker_pool`): nothing to run,
    as unpickling it imports this module, and with it the model build and the loop, before the
    first item."""
