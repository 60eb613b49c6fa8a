"""A robot's parts on the loop: what a part is handed when it is built, how it is built by name.

After dm_control's composer (an entity attaches itself to the hooks of the world it is added
to) and kiss-icp (the configuration is unpacked where a part is built): a
:class:`ComponentFactory` takes a :class:`Mount` and the run's
:class:`~amr_twin.model.config.TwinConfig`, and builds its part from the plain values it needs
(``cfg.imu``, a seed, a rate); the part then schedules itself on the clock, advertises on the
bus and hooks the loop's grid. It does not reach into the twin.

Sensors are components named in :attr:`amr_twin.assembly.twin.TwinOptions.sensors` and registered
in :data:`amr_twin.sensors.catalog.SENSORS`, PC-side nodes in ``TwinOptions.nodes`` and
:data:`amr_twin.assembly.nodes.NODES`; a third party registers its own there.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Protocol

from amr_twin.ros.bus import Bus
from amr_twin.base.clock import VirtualClock
from amr_twin.sim.hooks import Hooks

if TYPE_CHECKING:
    from amr_twin.model.config import TwinConfig
    from amr_twin.sim.physics import Physics

__all__ = ["ComponentFactory", "Mount"]


@dataclass(frozen=True)
class Mount:
    """What the loop hands a component when it is built.

    Attributes:
        physics: the robot's physics, to read by name (``model.sensor(name)``, ``pose()``,
            ``wheel_angles_rad()``); a component reads it and does not step it.
        clock: the loop's clock (us); a component schedules its events there.
        bus: the message bus the robot's parts publish on (its world's); a component advertises
            and subscribes there.
        hooks: the loop's hooks (``on_grid``, ``on_event``, ``on_actuation``, ...:
            :class:`~amr_twin.sim.hooks.Hooks`).
        grid_us: the record grid's period (the ``on_grid`` hook's instants), us.
        seed: the run's seed; a component draws from ``numpy.random.default_rng([seed, k])``
            with a ``k`` of its own.
        world: the world's name or path (:mod:`amr_twin.model.worlds`).
        actors: True when actors move in the world (people, pallet jacks).
    """

    physics: Physics
    clock: VirtualClock
    bus: Bus
    hooks: Hooks
    grid_us: int
    seed: int
    world: str
    actors: bool

    @property
    def samplers(self) -> list:
        """The loop's grid samplers (the ``on_grid`` hook's list), for a part whose sampler
        keeps its rows in C (:class:`~amr_twin.sim.grid_rows.GridRows`)."""
        return self.hooks.samplers


class ComponentFactory(Protocol):
    """Builds one part on ``mount`` from the values of ``cfg`` it needs; returns the part."""

    def __call__(self, mount: Mount, cfg: TwinConfig) -> object: ...
