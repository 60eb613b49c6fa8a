"""The navigation's plug-in points as protocols (nav2_core's Controller, GlobalPlanner, Behavior).

A plug-in is any class with these members; one that subclasses its protocol gets the defaults
(:meth:`LocalController.reset`, :attr:`LocalController.sees_people`, ...). Each kind is registered
by name in :mod:`amr_twin.navigation.registries`, where the stack finds it. The commands they give
(:class:`Twist2D`, :class:`Step`) are here too. Poses are ``(x_m, y_m, yaw_rad)`` in ``map``,
velocities ``(v_m_s, w_rad_s)``, times simulated s.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, ClassVar, Protocol

if TYPE_CHECKING:
    import numpy as np

    from amr_twin.navigation.path_handler import PathHandler
    from amr_twin.navigation.people import People
    from amr_twin.navigation.planner import Plan

__all__ = [
    "LocalController",
    "LocalisationSource",
    "Planner",
    "RecoveryBehaviour",
    "Step",
    "Twist2D",
]


@dataclass(frozen=True)
class Twist2D:
    """A command ``(v_m_s, w_rad_s)`` and whether the controller saw a collision ahead."""

    v_m_s: float
    w_rad_s: float
    blocked: bool = False


@dataclass
class Step:
    """One cycle of a recovery: the twist, and whether it has ended (and how)."""

    v_m_s: float = 0.0
    w_rad_s: float = 0.0
    done: bool = False
    failed: bool = False


class LocalController(Protocol):
    """Follows the plan every control cycle (nav2's controller plug-in): MPPI, RPP, a third party's.

    A factory ``(costmap, footprint, nav, seed) -> LocalController`` builds it (``nav``: the
    parameter file's ``navigation`` section); see
    :data:`~amr_twin.navigation.registries.CONTROLLERS`.
    """

    sees_people: ClassVar[bool] = False
    """Whether it steers round the tracked people itself; if not, it is given none (the collision
    monitor's people zones keep the robot from them)."""

    def command(
        self,
        pose: np.ndarray,
        velocity: tuple[float, float],
        path: PathHandler,
        people: People,
        t_s: float,
    ) -> Twist2D:
        """The twist for the robot at ``pose`` moving at ``velocity`` along ``path`` at ``t_s``,
        with the tracked ``people`` about; ``blocked`` when the way ahead is."""
        ...

    def reset(self) -> None:
        """Forget what the last cycles left (a turn in place, a recovery); default: nothing."""


class Planner(Protocol):
    """Plans from the robot to the goal on the costmap (nav2's global planner plug-in).

    A factory ``(costmap, footprint, nav) -> Planner`` builds it; see
    :data:`~amr_twin.navigation.registries.PLANNERS`.
    """

    people_m: float = 0.0
    """The robot's centre is kept this far from a standing person, m (the navigator leaves those
    nearer than this out: they stand at the robot)."""
    last_error: str = ""
    """Why the last plan failed, in one line."""

    def plan(
        self,
        start_xy_m: np.ndarray,
        goal_xy_m: np.ndarray,
        goal_yaw_rad: float | None = None,
        people_xy_m: np.ndarray | None = None,
    ) -> Plan | None:
        """A plan (:class:`~amr_twin.navigation.planner.Plan`) keeping clear of the people
        standing at ``people_xy_m`` (N, 2), or None (:attr:`last_error` says why)."""
        ...

    def path_free(self, xy_m: np.ndarray, people_xy_m: np.ndarray | None = None) -> bool:
        """Whether the rest of the present path ``xy_m`` (N, 2) is still free; default: no."""
        return False


class LocalisationSource(Protocol):
    """Where the navigator reads the robot's pose: a ``nav_msgs/Odometry`` topic on the bus.

    :meth:`attach` starts what publishes it on the twin; see
    :data:`~amr_twin.navigation.registries.LOCALISATIONS`.
    """

    topic: str
    """The bus topic of its ``nav_msgs/Odometry``."""
    in_map: bool = True
    """Its frame is ``map``; False: a frame that starts at the robot's start pose (``odom``)."""
    exact: bool = False
    """The true pose: no scan-to-map correction is applied to it."""
    takes_matches: bool = False
    """It takes the scan-to-map match in (:mod:`amr_twin.navigation.map_matching`'s feedback)."""

    def attach(self, twin, cfg) -> None:
        """Start the estimator that publishes :attr:`topic` on ``twin`` with ``cfg``'s settings;
        default: nothing (the topic is published already)."""


class RecoveryBehaviour(Protocol):
    """A recovery (nav2's behavior plug-in): :meth:`start`, then :meth:`step` each cycle till done.

    A factory ``(costmap, footprint, limits, dt_s, **settings) -> RecoveryBehaviour`` builds one at
    each failure; see :data:`~amr_twin.navigation.registries.RECOVERIES`.
    """

    def start(self, t_s: float, pose: np.ndarray) -> None:
        """Begin at ``t_s`` with the robot at ``pose``."""
        ...

    def step(self, t_s: float, pose: np.ndarray, velocity: tuple[float, float]) -> Step:
        """The twist of this cycle, and whether the recovery has ended."""
        ...
