"""The summary of a run (``amr-twin run --json``) as typed records, and the JSON written from them.

:func:`summary` measures a :class:`amr_twin.recording.run.RunResult` into a :class:`RunSummary`;
:meth:`RunSummary.as_json` is the ``--json`` object (strict JSON: NaN and inf become null).
Every RPM is signed, + = the wheel rolls forward (REP-103).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Optional, Union

if (
    TYPE_CHECKING
):  # numpy and the recorder (the model build) stay off the CLI's start-up path (--help)
    from amr_twin.analysis.metrics import StepInfo
    from amr_twin.recording.recorder import RunSeries

WHEEL_NAMES = ("left", "right")


@dataclass(frozen=True)
class Pose2:
    """A planar pose: x, y in metres, yaw in radians (the world frame, or odom)."""

    x_m: float
    y_m: float
    yaw_rad: float


@dataclass(frozen=True)
class WheelSummary:
    """One wheel over the run: what was asked, what it published, what it did.

    ``motion`` and ``reference_rpm`` of the wheel_Command (signed: motion x speed);
    ``final_rpm`` / ``final_rpm_t_s`` the last published speed and its time (0 / None when
    nothing was published); ``true_final_rpm`` the hinge's speed at the end; ``samples`` the
    speeds published; ``current_a_final`` the motor's mean current over the last second, A;
    ``current_a_peak`` its largest magnitude, A; ``step`` the step metrics of the published
    speed (a single command with a non-zero reference and two samples or more; None otherwise),
    with ``step_sign`` the reference's sign that the signed ones carry.
    """

    motion: int
    reference_rpm: float
    final_rpm: float
    final_rpm_t_s: Optional[float]
    true_final_rpm: float
    samples: int
    current_a_final: float
    current_a_peak: float
    step: Optional[StepInfo] = None
    step_sign: float = 1.0

    def as_json(self) -> dict:
        out = {
            "motion": self.motion,
            "reference_rpm": self.reference_rpm,
            "final_rpm": self.final_rpm,
            "final_rpm_t_s": self.final_rpm_t_s,
            "true_final_rpm": self.true_final_rpm,
            "samples": self.samples,
            "current_a_final": self.current_a_final,
            "current_a_peak": self.current_a_peak,
        }
        if self.step is not None:
            out.update(self.step.as_dict(sign=self.step_sign))
        return out


@dataclass(frozen=True)
class BatterySummary:
    """The pack over the run: mean current A, final terminal voltage V, energy drawn J, distance
    driven m and energy per metre J/m (None under 5 cm)."""

    battery_a_mean: float
    battery_v_final: float
    energy_j: float
    distance_m: float
    energy_j_per_m: Optional[float]


@dataclass(frozen=True)
class FromStart:
    """Where the run ended against its start pose: straight-line distance m, heading change deg."""

    distance_m: float
    heading_deg: float


@dataclass(frozen=True)
class RunSummary:
    """The ``--json`` object of a run.

    ``command``: the one command (a single run) or every command with its time (a mission);
    ``code``: the first non-zero of the client's ``codes``; ``collisions``: every contact episode
    of the robot's body with the world (:meth:`amr_twin.sim.collisions.Collision.as_dict`);
    ``stopped_by_collision``: the run ended at the first one; ``faults``: each injected fault with
    its effect (:meth:`amr_twin.sim.fault_injector.FaultInjector.report`); ``sim_s`` and ``wall_s``:
    simulated and wall-clock seconds; ``tyre_timestep``: the tyres' guard halved the physics
    timestep (:meth:`amr_twin.model.tyre_stability.TyreTimestep.as_dict`; absent when it did not).
    """

    command: Union[dict, list, None]
    wheel_command: Optional[list]
    code: int
    codes: list
    errors: list
    wheels: dict[str, WheelSummary]
    final_pose: Pose2
    final_odom_pose: Pose2
    battery: BatterySummary
    collisions: list = field(default_factory=list)
    stopped_by_collision: bool = False
    faults: list = field(default_factory=list)
    sim_s: float = 0.0
    wall_s: float = 0.0
    start_pose: Optional[Pose2] = None
    from_start: Optional[FromStart] = None
    tyre_timestep: Optional[dict] = None

    def as_json(self) -> dict:
        """The ``--json`` object (keys in this order; start_pose and from_start only when known)."""
        from dataclasses import asdict

        out = {
            "command": self.command,
            "wheel_command": self.wheel_command,
            "code": self.code,
            "codes": self.codes,
            "errors": self.errors,
            "wheels": {k: w.as_json() for k, w in self.wheels.items()},
            "final_pose": asdict(self.final_pose),
            "final_odom_pose": asdict(self.final_odom_pose),
            "battery": asdict(self.battery),
            "collisions": self.collisions,
            "stopped_by_collision": self.stopped_by_collision,
            "faults": self.faults,
            "sim_s": self.sim_s,
            "wall_s": self.wall_s,
        }
        if self.start_pose is not None:
            out["start_pose"] = asdict(self.start_pose)
        if self.from_start is not None:
            out["from_start"] = asdict(self.from_start)
        if self.tyre_timestep is not None:
            out["tyre_timestep"] = self.tyre_timestep
        return json_ready(out)


def json_ready(value):
    """``value`` with every non-finite float (NaN, inf) replaced by None, recursively (strict
    JSON)."""
    if isinstance(value, float) and not math.isfinite(value):
        return None
    if isinstance(value, dict):
        return {k: json_ready(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [json_ready(v) for v in value]
    return value


def summary(result, single: bool, start_xy_yaw=None) -> RunSummary:
    """Measure ``result`` (:class:`amr_twin.recording.run.RunResult`); ``single``: one command (its
    step metrics are measured) rather than a mission; ``start_xy_yaw``: the start pose, if known."""
    import numpy as np

    from amr_twin.recording.recorder import signed_published

    series, wc = result.series, result.wheel_command
    last_s = series.t_s >= series.t_s[-1] - 1.0  # "final" electrical values: the last second
    wheels = {}
    for w, name in enumerate(WHEEL_NAMES):
        reference = wc[2 * w] * wc[2 * w + 1] if wc else 0.0  # signed: motion x speed
        pub = signed_published(series, w)
        step = _step(pub, reference) if single else None
        wheels[name] = WheelSummary(
            motion=int(wc[2 * w]) if wc else 0,
            reference_rpm=reference,
            final_rpm=float(pub[-1, 1]) if len(pub) else 0.0,
            final_rpm_t_s=float(pub[-1, 0]) if len(pub) else None,
            true_final_rpm=float(series.true_rpm[-1, w]),
            samples=int(len(pub)),
            current_a_final=float(series.current_a[last_s, w].mean()),
            current_a_peak=float(np.abs(series.current_a[:, w]).max()),
            step=step,
            step_sign=1.0 if reference > 0 else -1.0,
        )
    commands = [dict(c.describe(), t_s=t) for t, c in result.commands]
    x, y, yaw = (float(v) for v in series.pose[-1])
    odom = series.odom[-1, 1:] if len(series.odom) else np.zeros(3)
    start = moved = None
    if start_xy_yaw is not None:
        sx, sy, syaw = start_xy_yaw
        start = Pose2(sx, sy, syaw)
        moved = FromStart(
            math.hypot(x - sx, y - sy), math.degrees(math.remainder(yaw - syaw, math.tau))
        )
    return RunSummary(
        command=(commands[0] if commands else None) if single else commands,
        wheel_command=wc,
        code=next((c for c in result.codes if c != 0), 0),
        codes=result.codes,
        errors=result.errors,
        wheels=wheels,
        final_pose=Pose2(x, y, yaw),
        final_odom_pose=Pose2(float(odom[0]), float(odom[1]), float(odom[2])),
        battery=_battery(series),
        collisions=result.collisions,
        stopped_by_collision=result.halted,
        faults=result.faults,
        sim_s=result.sim_s,
        wall_s=result.wall_s,
        start_pose=start,
        from_start=moved,
        tyre_timestep=result.tyre_timestep,
    )


def _step(pub, reference_rpm: float) -> Optional[StepInfo]:
    """Step metrics of a wheel's signed published speed ``pub`` (n, 2: t_s, rpm), or None."""
    from amr_twin.analysis.metrics import step_info

    if reference_rpm == 0.0 or len(pub) < 2:
        return None
    return step_info(pub[:, 0], pub[:, 1], reference_rpm)


def _battery(series: RunSeries) -> BatterySummary:
    """The pack over the run: mean current, final voltage, energy drawn and per metre driven."""
    import numpy as np

    power = series.battery_v * series.battery_a
    energy = float(np.sum(0.5 * (power[1:] + power[:-1]) * np.diff(series.t_s)))
    distance = float(np.sum(np.hypot(*np.diff(series.pose[:, :2], axis=0).T)))
    return BatterySummary(
        float(series.battery_a.mean()),
        float(series.battery_v[-1]),
        energy,
        distance,
        energy / distance if distance > 0.05 else None,
    )
