"""UMBmark on many robots: each seed's squares before and after its calibration, in parallel.

``amr-twin experiment umbmark --seeds 0:9`` takes, per seed, the robot the fusion experiment draws
(:func:`~amr_twin.experiments.fusion.robot.draw`: tyre radii, track and hall sensors within their
sourced tolerances), drives ``runs`` squares clockwise and ``runs`` counter-clockwise
(:func:`~amr_twin.experiments.umbmark.square.drive_square`), each run a fresh twin at the origin
with its own seed (the floor's friction field and the hall edges' jitter), computes UMBmark
(:func:`~amr_twin.experiments.umbmark.experiment.umbmark`), writes the calibration the odometry node
then uses (:func:`~amr_twin.experiments.umbmark.experiment.calibration`) and drives the squares
again with it.

Besides the odometry node's return errors (what UMBmark measures on the robot), each phase keeps
UMBmark of the parts of those errors (:class:`Phase`): the wheels' true angles integrated with the
geometry the odometry assumes (geometry and tyre slip) and with the true one (the slip alone); the
rest is the odometry's sampling of the speeds. The seeds run in the project's process pool
(:func:`~amr_twin.experiments.runner.executor.run_all`); results come back in the order of the
seeds."""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from amr_twin.controllers.odometry_calibration import OdometryCalibration
from amr_twin.model.config import TwinConfig
from amr_twin.experiments.fusion import robot as fusion_robot
from amr_twin.experiments.runner.executor import run_all
from amr_twin.experiments.umbmark.experiment import Umbmark, calibration, umbmark
from amr_twin.experiments.umbmark.square import DIRECTIONS, Profile, SquareRun, drive_square

MAX_RUNS = 50
"""Most squares per direction and phase (each ~1 s of CPU)."""
SQUARE_S = 60.0
"""Simulated time of one square, s (four legs of 4 m at up to 0.4 m/s, four turns, the rests: 59-61
s)."""
STREAM = 30
"""First entry of every run's seed sequence (the squares): ``[STREAM, seed, phase, direction,
run]``."""


@dataclass(frozen=True)
class Phase:
    """One set of squares (before or after the calibration) and UMBmark of their return errors:
    the odometry node's (``node``), its geometry-and-slip part (``wheels``: the true wheel angles
    with the geometry the odometry assumes), its slip part (``slip``: with the true geometry) and
    its sampling part (``sampling``: the wheels' pose minus the node's)."""

    runs: tuple[SquareRun, ...]
    node: Umbmark
    wheels: Umbmark
    slip: Umbmark
    sampling: Umbmark


@dataclass(frozen=True)
class SeedResult:
    """One robot: its drawn errors, the squares before and (unless ``after`` is None) after the
    calibration written for its odometry node, and the CPU time spent, s."""

    seed: int
    robot: fusion_robot.RobotErrors
    tyres: bool
    before: Phase
    calibration: OdometryCalibration | None
    after: Phase | None
    cpu_s: float

    @property
    def reduction(self) -> float | None:
        """E_max,syst before over after (None without an after phase)."""
        if self.after is None:
            return None
        return self.before.node.e_max_syst_m / self.after.node.e_max_syst_m


@dataclass(frozen=True)
class SeedJob:
    """One seed's work (picklable, for a pool worker)."""

    cfg: TwinConfig
    seed: int
    runs: int
    profile: Profile = Profile()
    calibrate: bool = True

    @property
    def squares(self) -> int:
        return 2 * self.runs * (2 if self.calibrate else 1)


def run_seed_of(seed: int, phase: int, direction: str, run: int) -> int:
    """The seed of one square's twin (friction field, hall jitter): different for every square."""
    entropy = [STREAM, int(seed), int(phase), DIRECTIONS.index(direction), int(run)]
    return int(np.random.SeedSequence(entropy).generate_state(1)[0])


def _phase(
    cfg: TwinConfig,
    robot: fusion_robot.RobotErrors,
    job: SeedJob,
    phase: int,
    odometry: OdometryCalibration | None,
) -> Phase:
    from amr_twin.assembly.twin import Twin, TwinOptions

    runs = []
    for direction in DIRECTIONS:
        for k in range(job.runs):
            options = TwinOptions(
                firmware="improved",
                world="empty",
                seed=run_seed_of(job.seed, phase, direction, k),
                visuals=False,
                odometry_calibration=odometry,
                **robot.twin_options(),
            )
            runs.append(drive_square(Twin(cfg, options), direction, job.profile, run=k))
    w = cfg.wheel
    side, b = job.profile.side_m, w.separation_m

    def of(error) -> Umbmark:
        return umbmark(
            [error(r) for r in runs if r.direction == "cw"],
            [error(r) for r in runs if r.direction == "ccw"],
            side,
            b,
        )

    def sampling(r: SquareRun) -> tuple[float, float]:
        return (r.error_m[0] - r.wheels_error_m[0], r.error_m[1] - r.wheels_error_m[1])

    return Phase(
        tuple(runs),
        of(lambda r: r.error_m),
        of(lambda r: r.wheels_error_m),
        of(lambda r: r.slip_error_m),
        of(sampling),
    )


def run_seed(job: SeedJob) -> SeedResult:
    """UMBmark of seed ``job.seed``'s robot: the squares, the calibration, the squares again."""
    t0 = time.process_time()
    robot = fusion_robot.draw(job.cfg, job.seed)
    cfg = robot.config(job.cfg)
    w = cfg.wheel
    before = _phase(cfg, robot, job, 0, None)
    cal = after = None
    if job.calibrate:
        nominal = OdometryCalibration(w.radius_m, w.radius_m, w.separation_m)
        u = before.node
        cal = calibration(
            u,
            nominal,
            source=f"amr-twin experiment umbmark, seed {job.seed}, {job.runs} runs a "
            f"direction (E_d {u.e_d:.6f}, E_b {u.e_b:.6f})",
        )
        after = _phase(cfg, robot, job, 1, cal)
    return SeedResult(
        job.seed, robot, bool(w.tyre_slip), before, cal, after, time.process_time() - t0
    )


def run(
    jobs_list: list[SeedJob],
    jobs: int = 1,
    progress: bool = True,
    description: str = "umbmark squares",
) -> list[SeedResult]:
    """Run every seed's job (``jobs`` local workers); results in the order given."""
    done = {
        (j.seed, j.calibrate, j.cfg.wheel.tyre_slip): r
        for j, r in run_all(
            run_seed,
            jobs_list,
            jobs=jobs,
            description=description,
            progress=progress,
            size=lambda j: j.squares,
        )
    }
    return [done[(j.seed, j.calibrate, j.cfg.wheel.tyre_slip)] for j in jobs_list]
