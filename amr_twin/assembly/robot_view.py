"""One robot of a world seen as a lone twin: :class:`RobotView`, the hooks and observables of
one :class:`~amr_twin.assembly.robot.Robot` for the code downstream of the loop (recorders, live
views) that was written for a :class:`~amr_twin.assembly.twin.Twin`.

A fleet's robots speak on buses of their own and have their own columns of the loop's rows
(:class:`~amr_twin.assembly.world.World`); the view gives a consumer the robot's bus, its
observables and its columns of the grid rows, the world's grid and clock, so that it needs no
reaching into the robot's parts.
"""

from __future__ import annotations


class RobotView:
    """The robot ``robot`` of ``world`` (a :class:`~amr_twin.assembly.world.World`) with the hooks
    and attributes of a lone :class:`~amr_twin.assembly.twin.Twin` that the capture, the recorder,
    the event log and the live rows read (module notes); ``name`` its ROS namespace (None: its
    name in the model)."""

    def __init__(self, world, robot, name: str | None = None):
        self.world, self.robot = world, robot
        self.name = robot.name if name is None else name
        """The robot's name, its namespace (``amr-2``)."""
        self.prefix = robot.physics.prefix
        """Its names' prefix in the model (``amr-2/``)."""
        self.start_xy_yaw = robot.start_xy_yaw
        """Where it started (m, m, rad), where its odometry's ``odom`` lies."""
        self.cfg, self.bus = robot.spec.cfg, robot.bus
        self.observables, self.sensors = robot.observables, robot.sensors
        self.collisions, self.faults = robot.collisions, robot.faults
        self.actors = None
        """No actors of its own: the world's people are not one robot's topics."""
        self.grid_every, self.grid_us = world.grid_every, world.grid_us
        self._columns = robot.physics.loop_columns

    @property
    def t_phys_us(self) -> int:
        """The world's physics time, us."""
        return self.world.t_phys_us

    def on_grid(self, sampler):
        """The world's grid hook."""
        return self.world.on_grid(sampler)

    def on_actuation(self, fn):
        """The world's actuation hook (any robot's pins: ``fn`` reads this robot's)."""
        return self.world.on_actuation(fn)

    def on_message(self, tap, topics: tuple[str, ...] | None = None):
        """Tap the robot's own bus."""
        self.robot.bus.add_tap(tap, topics=topics)
        return tap

    def on_grid_rows(self, fn):
        """Call ``fn(t_us, rows)`` with this robot's columns of the world's grid rows."""
        columns = self._columns

        def robot_rows(t_us, rows) -> None:
            fn(t_us, [row[columns] for row in rows])

        self.world.on_grid_rows(robot_rows)
        return robot_rows

    def unhook(self, fn) -> None:
        """Remove ``fn`` from the world's hooks or the robot's bus."""
        if self.robot.bus.has_tap(fn):
            self.robot.bus.remove_tap(fn)
        else:
            self.world.unhook(fn)
