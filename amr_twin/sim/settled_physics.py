"""Built and settled physics, kept for the next twin of the same robot in the same place.

A payload sweep runs each configuration once per command, and chapter 5 and the tests
start many twins of one configuration: each would build and compile the same model
and let it settle the same half second (about 15 ms of a sweep point's 200). The
physics of the first, copied as it settled (MuJoCo copies the model and the data,
contacts and constraint forces included, in C), serves the next: stepping on from a
copy gives the same bits as stepping on from the original, and each twin gets its own
copy to change (motor modes, rolling resistance, faults).

Kept: the last :data:`KEEP` settled models of this process, by configuration, world,
start pose, visuals, IMU sensors, actors and settling time; built-in worlds only (a world file
may change between runs). A configuration that cannot be hashed is built every time.

Part of the physics layer (``PHYSICS_LAYER``): builds the settled Physics of a run (MjData's time
reset after settling).
"""

from __future__ import annotations

from collections import OrderedDict
from pathlib import Path

from amr_twin.model.build import build
from amr_twin.model.config import TwinConfig
from amr_twin.sim.start_pose import check_start, check_supported
from amr_twin.sim.physics import Physics

PHYSICS_LAYER = True

KEEP = 2
"""Settled models kept (a sweep's points of one configuration come one after the other)."""

_kept: OrderedDict = OrderedDict()


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
    key = None
    if not Path(str(world)).suffix:
        key = (
            cfg,
            str(world),
            tuple(start_xy_yaw),
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
            return kept[0].clone(), kept[1]
    built = build(
        cfg,
        world,
        start_xy_yaw,
        visuals=visuals,
        imu=imu,
        actors=tuple(actors),
        obstacles=tuple(obstacles),
    )
    physics = Physics(built.model)
    check_start(physics, where)
    physics.settle(settle_s)
    check_supported(physics, where)
    physics.data.time = 0.0
    if key is not None:
        _kept[key] = (physics.clone(), built.urdf)
        while len(_kept) > KEEP:
            _kept.popitem(last=False)
    return physics, built.urdf


def forget() -> None:
    """Drop the kept models (the next twin of each configuration builds it again)."""
    _kept.clear()
