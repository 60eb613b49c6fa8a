"""Built and settled physics, kept for the next twin of the same robots in the same place.

A payload sweep runs each configuration once per command, and chapter 5 and the tests
start many twins of one configuration: each would build and compile the same model
and let it settle the same half second (about 15 ms of a sweep point's 200). The
physics of the first, copied as it settled (MuJoCo copies the model and the data,
contacts and constraint forces included, in C), serves the next: stepping on from a
copy gives the same bits as stepping on from the original, and each twin gets its own
copy to change (motor modes, rolling resistance, faults).

Kept: the last :data:`KEEP` settled models of this process, by configuration, world,
start poses, visuals, IMU sensors, actors and settling time; built-in worlds only (a world file
may change between runs). A configuration that cannot be hashed is built every time.

A world of several robots (:func:`settled_fleet`) settles them together: a :class:`Fleet`, one
:class:`~amr_twin.sim.physics.Physics` per robot on one MjData.

Part of the physics layer (``PHYSICS_LAYER``): builds the settled Physics of a run (MjData's time
reset after settling).
"""

from __future__ import annotations

import math
from collections import OrderedDict
from dataclasses import dataclass
from pathlib import Path

from amr_twin.model.build import build
from amr_twin.model.config import TwinConfig
from amr_twin.model.robot_starts import ROBOT_PREFIX, RobotStart
from amr_twin.sim.start_pose import check_start, check_supported
from amr_twin.sim.physics import Physics

PHYSICS_LAYER = True

KEEP = 2
"""Settled models kept (a sweep's points of one configuration come one after the other)."""

_kept: OrderedDict = OrderedDict()


@dataclass(frozen=True)
class Fleet:
    """The settled physics of a world's robots: :attr:`robots` (one Physics each, in the order of
    :attr:`starts`, sharing one MjData) and the robot's URDF."""

    robots: tuple[Physics, ...]
    starts: tuple[RobotStart, ...]
    urdf: str

    @property
    def world(self) -> Physics:
        """The Physics the world steps through (the first robot's: stepping any steps all)."""
        return self.robots[0]

    @property
    def loop_width(self) -> int:
        """Values of a grid loop row that holds every robot's loop sensors
        (:class:`~amr_twin.sim.grid_loop.GridLoop`'s ``width``)."""
        return max(p.loop_columns.stop for p in self.robots)

    def robot_rows(self, rows: list, index: int) -> list:
        """The loop-sensor rows of robot ``index`` (0-based) from a grid loop's ``rows``."""
        columns = self.robots[index].loop_columns
        return [row[columns] for row in rows]

    def clone(self) -> "Fleet":
        """An independent copy in its present state (:meth:`Physics.clone`), views and all."""
        first = self.robots[0].clone()
        return Fleet(
            (first, *(first.robot(p.prefix) for p in self.robots[1:])), self.starts, self.urdf
        )


def settled_physics(
    cfg: TwinConfig,
    world: str,
    start_xy_yaw: tuple[float, float, float],
    visuals: bool,
    imu: bool,
    settle_s: float,
    where: str,
    actors: tuple = (),
    obstacles: tuple = (),
) -> tuple[Physics, str]:
    """``(physics, urdf)``: the robot built in ``world`` at ``start_xy_yaw`` (x_m, y_m, yaw_rad)
    with ``actors`` (:class:`~amr_twin.model.actors.Actor`, standing at their poses at t = 0) and
    ``obstacles`` (:class:`~amr_twin.model.worlds.Obstacle`, unmapped boxes),
    checked clear of the world (``where`` names the start in the errors), settled for
    ``settle_s`` with its motors braked and its clock set back to 0; a copy of a kept one when
    the same was settled before."""
    start = RobotStart(ROBOT_PREFIX, *start_xy_yaw)
    fleet = _settled(cfg, world, (start,), (where,), visuals, imu, settle_s, actors, obstacles)
    return fleet.world, fleet.urdf


def settled_fleet(
    cfg: TwinConfig,
    world: str,
    starts: tuple[RobotStart, ...],
    visuals: bool,
    imu: bool,
    settle_s: float,
    actors: tuple = (),
    obstacles: tuple = (),
) -> Fleet:
    """:func:`settled_physics` of a robot per start (:func:`~amr_twin.model.robot_starts.
    fleet_starts`): each start checked clear of the world and of the other robots
    (:class:`~amr_twin.sim.start_pose.StartPoseError` naming the robot), all settled together."""
    wheres = tuple(
        f"{s.name} start {s.x_m:g},{s.y_m:g},{math.degrees(s.yaw_rad):g}" for s in starts
    )
    return _settled(cfg, world, tuple(starts), wheres, visuals, imu, settle_s, actors, obstacles)


def _settled(cfg, world, starts, wheres, visuals, imu, settle_s, actors, obstacles) -> Fleet:
    key = None
    if not Path(str(world)).suffix:
        key = (
            cfg,
            str(world),
            starts,
            bool(visuals),
            bool(imu),
            float(settle_s),
            tuple(actors),
            tuple(obstacles),
        )
        try:
            kept = _kept.get(key)
        except TypeError:  # an unhashable configuration: build it
            kept = key = None
        if kept is not None:
            _kept.move_to_end(key)
            return kept.clone()
    built = build(
        cfg,
        world,
        visuals=visuals,
        imu=imu,
        actors=tuple(actors),
        obstacles=tuple(obstacles),
        robots=starts,
    )
    first = Physics(built.model, starts[0].prefix)
    fleet = Fleet((first, *(first.robot(s.prefix) for s in starts[1:])), starts, built.urdf)
    for physics, where in zip(fleet.robots, wheres):
        check_start(physics, where)
    for physics in fleet.robots:  # the settling of Physics.settle, every robot braked
        for wheel in range(2):
            physics.motors.set(wheel, "brake")
    first.step(int(round(settle_s / first.timestep_s)))
    first.check()
    for physics, where in zip(fleet.robots, wheres):
        check_supported(physics, where)
    first.data.time = 0.0
    if key is not None:
        _kept[key] = fleet.clone()
        while len(_kept) > KEEP:
            _kept.popitem(last=False)
    return fleet


def forget() -> None:
    """Drop the kept models (the next twin of each configuration builds it again)."""
    _kept.clear()
